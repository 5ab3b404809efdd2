"""The MuJoCo engine's compiled world, as functions of the engine: the compile in place
(``MjSpec.recompile``, keeping the state) and the geom and qpos rows read from it."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco.entities import MUJOCO_ERRORS, mujoco_error
from galton.daemon.engines.mujoco.state import FREE

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def compile_in_place(engine: MujocoEngine, nbody: int | None, nv: int | None) -> None:
    """Compile the edited spec in place, keeping the state, with an arena for ``nbody``
    bodies and ``nv`` degrees of freedom (the model's own by default). On failure the
    model and data in use are untouched; raise with MuJoCo's words. (Reindex after.)"""
    engine.xml = None
    m, spec = engine.model, engine.mj_spec
    memory = spec.memory
    spec.memory = ms.arena_bytes(m.nbody if nbody is None else nbody, m.nv if nv is None else nv)
    try:
        engine.model, engine.data = spec.recompile(engine.model, engine.data)
    except MUJOCO_ERRORS as exc:
        spec.memory = memory
        raise mujoco_error(exc, "MuJoCo rejected the change") from exc
    engine.workers = 0  # the recompiled MjData has no thread pool
    engine.parked_edited = False
    engine.start_workers()


def geom_ids(engine: MujocoEngine, names: Sequence[str]) -> np.ndarray:
    """Every geom of these entities: a spawned body's one, a model's whole subtree."""
    m = engine.model
    ids = engine.body_ids(names)
    spawned = np.fromiter((engine.entities[n].source == "spawn" for n in names), dtype=bool,
                          count=len(names))
    gids = [m.body_geomadr[ids[spawned]]]
    if not spawned.all():
        gids.append(np.flatnonzero(np.isin(m.body_rootid[m.geom_bodyid], ids[~spawned])))
    return np.concatenate(gids)


def watched_rows(engine: MujocoEngine) -> np.ndarray:
    """qpos rows of the entities' free bodies' positions (parked ones are no entities)."""
    ids = np.fromiter(engine.ids.values(), dtype=np.int64, count=len(engine.ids))
    free = ids[engine.index.kind[ids] == FREE]
    rows: np.ndarray = (engine.index.qadr[free][:, None] + np.arange(3)).ravel()
    return rows
