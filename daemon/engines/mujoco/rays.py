"""Ray casts in a MuJoCo world (``mj_ray``, ``mj_multiRay``), hitting entities only.

Only entities' geoms count: a parked body's geom (``parked``) is no entity's and
is never hit. Every other geom counts whatever its group or whether its body is
static or asleep; MuJoCo itself skips a geom whose colour is fully transparent.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

from galton.daemon.engines.mujoco.entities import geom_entities
from galton.daemon.engines.mujoco.render import HIDDEN, SHOWN

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# A ray leaving a shape it started in is cast again from this far past the surface, at
# most this many times (nested shapes).
STEP_PAST = 1e-9
EXIT_TRIES = 8
# Rays sharing one origin go to mj_multiRay when they are at least this many per origin.
MULTI_RAY_MIN = 8
_SHOWN_ONLY = np.array([1 if g == SHOWN else 0 for g in range(6)], np.uint8)


def cast_rays(engine: MujocoEngine, origins: np.ndarray, directions: np.ndarray,
              max_length: float
              ) -> tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Engine.raycast at the current positions (see the module docstring)."""
    m, d = engine.model, engine.data
    mujoco.mj_kinematics(m, d)
    names, label = geom_entities(m, engine.ids)
    geom, dist, normal = raycast(m, d, label >= 0, origins, directions, max_length)
    hit = geom >= 0
    points = np.where(hit[:, None], origins + directions * dist[:, None], np.nan)
    return (hit, [names[label[g]] if g >= 0 else "" for g in geom], points,
            np.where(hit[:, None], normal, np.nan), np.where(hit, dist, np.nan))


def raycast(model: mujoco.MjModel, data: mujoco.MjData, shown: np.ndarray,
            origins: np.ndarray, directions: np.ndarray, max_length: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each ray's geom id (-1: none within max_length), distance and normal, among the
    ``shown`` geoms (geom groups swapped for the casts, then put back)."""
    n = len(origins)
    geom = np.full(n, -1, np.int32)
    dist = np.full(n, -1.0)
    normal = np.zeros((n, 3))
    groups = model.geom_group.copy()
    model.geom_group[:] = np.where(shown, SHOWN, HIDDEN)
    try:
        origins = np.ascontiguousarray(origins, float)
        directions = np.ascontiguousarray(directions, float)
        _cast(model, data, origins, directions, geom, dist, normal)
        _past_exits(model, data, origins, directions, geom, dist, normal)
    finally:
        model.geom_group[:] = groups
    geom[(dist < 0) | (dist > max_length)] = -1
    return geom, dist, normal


def _past_exits(model: mujoco.MjModel, data: mujoco.MjData, origins: np.ndarray,
                directions: np.ndarray, geom: np.ndarray, dist: np.ndarray,
                normal: np.ndarray) -> None:
    """A ray does not see a shape it starts inside (docs/protocol.md, ``raycast``), as
    Bullet's rays do not: where MuJoCo reports a ray leaving a shape (its outward normal
    along the ray), the ray is cast again from just past that point, at most EXIT_TRIES
    times (then it misses)."""
    for tries in range(EXIT_TRIES + 1):
        leaving = np.flatnonzero((geom >= 0) & (np.sum(normal * directions, axis=1) > 0.0))
        if not len(leaving):
            return
        if tries == EXIT_TRIES:
            geom[leaving] = -1
            return
        past = dist[leaving] + STEP_PAST
        ids, more, normals = np.full(len(leaving), -1, np.int32), np.full(
            len(leaving), -1.0), np.zeros((len(leaving), 3))
        starts = np.ascontiguousarray(origins[leaving] + directions[leaving] * past[:, None])
        _cast(model, data, starts, np.ascontiguousarray(directions[leaving]), ids, more,
              normals)
        geom[leaving], normal[leaving] = ids, normals
        dist[leaving] = np.where(more >= 0, more + past, -1.0)


def _cast(model: mujoco.MjModel, data: mujoco.MjData, origins: np.ndarray,
          directions: np.ndarray, geom: np.ndarray, dist: np.ndarray,
          normal: np.ndarray) -> None:
    """mj_multiRay for rays from a shared origin, mj_ray one by one for the rest."""
    unique, which, counts = np.unique(origins, axis=0, return_inverse=True,
                                      return_counts=True)
    which = which.ravel()
    single = counts[which] < MULTI_RAY_MIN
    for k in np.flatnonzero(counts >= MULTI_RAY_MIN):
        rows = np.flatnonzero(which == k)
        ids = np.empty(len(rows), np.int32)
        d = np.empty(len(rows))
        nrm = np.empty(3 * len(rows))
        mujoco.mj_multiRay(model, data, unique[k], directions[rows].ravel(), _SHOWN_ONLY,
                           True, -1, ids, d, nrm, len(rows), np.inf)
        geom[rows], dist[rows], normal[rows] = ids, d, nrm.reshape(-1, 3)
    one = np.empty(1, np.int32)
    for i in np.flatnonzero(single):
        dist[i] = mujoco.mj_ray(model, data, origins[i], directions[i], _SHOWN_ONLY, True,
                                -1, one, normal[i])
        geom[i] = one[0]
