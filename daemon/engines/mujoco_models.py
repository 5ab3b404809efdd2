"""Loading MJCF models into the MuJoCo world, as functions of the engine.

Every top-level body of the model becomes an entity; its inner bodies' names stay taken
while it lives. Attaching cannot be undone, so it is tried on a copy of the spec first.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines import mujoco_pool as mp
from galton.daemon.engines import mujoco_spec as ms
from galton.daemon.engines import mujoco_state as mst
from galton.daemon.engines.mujoco_entity import MUJOCO_ERRORS, WORLD, Entity, mujoco_error
from galton.daemon.engines.mujoco_state import JOINTED
from galton.protocol import (
    EntityInfo,
    FeatureUnsupportedError,
    GaltonError,
    NameNotUniqueError,
)

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco_engine import MujocoEngine


def load_model(engine: MujocoEngine, fmt: str, text: str | None, path: str | None,
               prefix: str) -> list[EntityInfo]:
    """Attach an MJCF model's bodies to the spec, tried on a copy first; one recompile."""
    if fmt != "mjcf":
        raise FeatureUnsupportedError(f"model format {fmt!r} is not supported by MuJoCo "
                                      "here; supported: mjcf")
    child = ms.parse_mjcf(text, path)
    tops, parts = ms.model_names(child, prefix)
    check_model_names(engine, [*tops, *(n for names in parts for n in names)])
    try:
        trial = engine._spec.copy()  # attaching cannot be undone: try it on a copy first
        trial.attach(child.copy(), prefix=prefix, frame=trial.worldbody.add_frame())
        size = trial.compile()
    except MUJOCO_ERRORS as exc:
        raise mujoco_error(exc, "the MJCF model does not fit this world") from exc
    frame = engine._spec.worldbody.add_frame()
    try:
        engine._spec.attach(child, prefix=prefix, frame=frame)
        for name, inner in zip(tops, parts, strict=True):
            body = engine._spec.body(name)
            engine._entities[name] = Entity(body, static=bool(body.mocap), source="model",
                                            parts=inner)
        engine._recompile(size.nbody, size.nv)
    except (GaltonError, *MUJOCO_ERRORS) as exc:
        for name in tops:
            engine._entities.pop(name, None)
        mp.remove_frame(engine._spec, frame)  # with the model's bodies and what uses them
        if isinstance(exc, GaltonError):
            raise
        raise mujoco_error(exc, "the MJCF model does not fit this world") from exc
    engine._models += len(tops)
    engine._parts.update(n for names in parts for n in names)
    return [model_info(engine, name) for name in tops]


def check_model_names(engine: MujocoEngine, names: Sequence[str]) -> None:
    """Refuse a model whose bodies' names are taken, or the engine's own."""
    for name in names:
        if name in engine._entities or name in engine._parts or name == WORLD or \
                name.startswith(mp.PREFIX):
            raise NameNotUniqueError(
                f"the model's body {name!r} has the name of a body already in the MuJoCo "
                "world; load it with another prefix")


def model_info(engine: MujocoEngine, name: str) -> EntityInfo:
    """A loaded entity as the World lists it; a jointed one's pose kept as its initial."""
    bid = engine._ids[name]
    entity = engine._entities[name]
    if engine._index.kind[bid] == JOINTED:
        poses, _ = mst.jointed_states(engine._model, engine._data, np.array([bid]))
        entity.initial_pose = poses[0]
    return EntityInfo(name=name, shape="model", static=entity.static,
                      mass=float(engine._model.body_subtreemass[bid]), source="model")
