"""Taking bodies out of the MuJoCo world: ``delete`` and ``clear``, as functions of the engine.

Spawned bodies still of their pool kind are parked (no compile while they all fit in the
pool); the others leave the spec, and one recompile follows. Removed bodies cannot be put
back, so a delete in a world holding a loaded model (whose references may reach other
bodies) is first tried on a copy of the spec.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco import parked as mp
from galton.daemon.engines.mujoco.entities import (
    MUJOCO_ERRORS,
    Entity,
    drop_assets,
    mujoco_error,
)
from galton.protocol import GaltonError, InvalidArgumentError, OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def delete(engine: MujocoEngine, names: Sequence[str]) -> None:
    """Spawned bodies still of their kind go back to the pool, parked (no compile while
    they all fit); the others leave the spec, and one recompile follows."""
    ids = engine.body_ids(names)
    entities = [engine.entities[n] for n in names]
    for name, entity in zip(names, entities, strict=True):
        if entity.source == "link":
            raise InvalidArgumentError(f"entity {name!r} is a link of the model "
                                       f"{entity.model!r}: delete the model")
    parked, removed = engine.parked.split(entities)
    if removed and engine.models:
        try_removing(engine.mj_spec, removed)
    for name, entity in zip(names, entities, strict=True):
        forget(engine, name, entity)
    if put_away(engine, parked, removed):
        try:
            engine.recompile()
        except GaltonError as exc:
            engine.broken = True  # the bodies are out of the spec, not of the model
            raise OperationFailedError(
                f"MuJoCo failed to recompile after a delete ({exc}); the world must be "
                "reset") from exc
        park = np.array([e.body.id for e in parked], dtype=np.int64)
    else:
        chosen = {id(e) for e in parked}
        park = ids[[i for i, e in enumerate(entities) if id(e) in chosen]]
        engine.parked_edited |= bool(len(park))
        if engine.sleep_guard is not None:
            engine.sleep_guard.forget(engine.model, engine.model.body_treeid[park])
    mp.park_arrays(engine.model, engine.data, engine.index, park)
    engine.wrenches.apply(engine.data, engine.ids)


def clear(engine: MujocoEngine) -> None:
    """An empty world at time 0; the pool stays warm: every spawned body is parked."""
    engine.restart_looks()  # held balls get their sleep policy back: the model may stay
    entities = list(engine.entities.values())
    engine.entities.clear()
    engine.wrenches.drop(None)
    engine.diverged = False
    engine.observed = None
    if engine.models or engine.broken:
        engine.build_empty()  # a model may bring more than bodies: start afresh
        return
    parked, removed = engine.parked.split(entities)
    if put_away(engine, parked, removed):
        try:
            engine.recompile()
        except GaltonError:
            engine.build_empty()
            return
    else:
        engine.parked_edited |= bool(parked)
    mp.park_arrays(engine.model, engine.data, engine.index,
                   np.array([e.body.id for e in parked], dtype=np.int64))
    mujoco.mj_resetData(engine.model, engine.data)
    engine.reindex()


def put_away(engine: MujocoEngine, parked: Sequence[Entity],
             removed: Sequence[Entity]) -> bool:
    """Park what the pool takes and take the rest out of the spec; whether a recompile
    must follow."""
    engine.parked.park(parked)
    if removed:
        mp.remove_bodies(engine.mj_spec, [e.body for e in removed], sweep(engine))
        drop_assets(engine.mj_spec, list(removed))
    return bool(removed) or gravcomp_missing(engine.model, parked)


def forget(engine: MujocoEngine, name: str, entity: Entity) -> None:
    """Strike an entity (with a model's links, joints and targets) from the engine's
    records, and its wrenches."""
    for gone in (name, *entity.parts):
        del engine.entities[gone]
        del engine.ids[gone]
    engine.wrenches.drop([name, *entity.parts])
    engine.loaded_joints.forget_model(name)
    engine.watch = None
    engine.parts.difference_update(entity.parts)
    engine.models -= entity.source == "model"


def sweep(engine: MujocoEngine) -> list[Any]:
    """The empty frames (see parked.Additions.bodies), handed over to be deleted."""
    empty_frames, engine.empty_frames = engine.empty_frames, []
    return empty_frames


def gravcomp_missing(model: mujoco.MjModel, parked: Sequence[Entity]) -> bool:
    """Whether parking these needs a recompile: a model compiled without any gravity
    compensation ignores the body_gravcomp that holds parked bodies up."""
    return model.ngravcomp == 0 and not all(e.static for e in parked)


def try_removing(spec: mujoco.MjSpec, removed: Sequence[Entity]) -> None:
    """Compile a copy of the spec without these bodies; raise, changing nothing, if
    MuJoCo refuses it."""
    trial = spec.copy()
    mp.remove_bodies(trial, [trial.body(e.body.name) for e in removed])
    try:
        trial.compile()
    except MUJOCO_ERRORS as exc:
        raise mujoco_error(exc, "MuJoCo cannot delete these bodies") from exc
