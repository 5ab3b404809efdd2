"""What a MuJoCo world's entities show to rays and what touches what: ray casts, contacts.

Only entities' geoms count: a parked pool body's geom (``pool``) is no entity's and
is never hit nor reported. Every other geom counts whatever its group or whether its body is
static or asleep; MuJoCo itself skips a geom whose colour is fully transparent.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from galton.daemon.engines.base import CameraView
from galton.daemon.engines.mujoco.render import HIDDEN, SHOWN, CameraRig

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# A ray leaving a shape it started in is cast again from this far past the surface, at
# most this many times (nested shapes).
STEP_PAST = 1e-9
EXIT_TRIES = 8
# Rays sharing one origin go to mj_multiRay when they are at least this many per origin.
MULTI_RAY_MIN = 8
_SHOWN_ONLY = np.array([1 if g == SHOWN else 0 for g in range(6)], np.uint8)


def render(engine: MujocoEngine, cameras: Sequence[CameraView]
           ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
    """The cameras' images at the current positions; labels are the entities seen."""
    if not cameras:
        return [], []
    if engine._cameras is None:
        engine._cameras = CameraRig()
    m, d = engine._model, engine._data
    mujoco.mj_kinematics(m, d)  # the data's poses are from before the last step's move
    names, label = geom_entities(m, engine._ids)
    images = engine._cameras.render(m, d, label >= 0, label, cameras)
    seen = np.unique(np.concatenate([im["segmentation"].ravel() for im in images
                                     if "segmentation" in im] or [np.empty(0, np.int32)]))
    seen = seen[seen >= 0]
    compact = np.full(len(names) + 1, -1, np.int32)  # the last entry maps -1 to -1
    compact[seen] = np.arange(len(seen))
    for im in images:
        if "segmentation" in im:
            im["segmentation"] = compact[im["segmentation"]]
    return images, [names[i] for i in seen]


def cast_rays(engine: MujocoEngine, origins: np.ndarray, directions: np.ndarray,
              max_length: float
              ) -> tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]:
    """Engine.raycast at the current positions (see the module docstring)."""
    m, d = engine._model, engine._data
    mujoco.mj_kinematics(m, d)
    names, label = geom_entities(m, engine._ids)
    geom, dist, normal = raycast(m, d, label >= 0, origins, directions, max_length)
    hit = geom >= 0
    points = np.where(hit[:, None], origins + directions * dist[:, None], np.nan)
    return (hit, [names[label[g]] if g >= 0 else "" for g in geom], points,
            np.where(hit[:, None], normal, np.nan), np.where(hit, dist, np.nan))


def touching(engine: MujocoEngine, names: Sequence[str] | None
             ) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Engine.contacts: the last step's contacts (see ``contacts``)."""
    if names is not None:
        engine._body_ids(names)  # NotFoundError for a name that is no entity's
    m = engine._model
    labels, label = geom_entities(m, engine._ids)
    return contacts(m, _awake_view(m, engine._data, engine._ids), label, labels, names)


def _awake_view(model: mujoco.MjModel, data: mujoco.MjData, ids: Mapping[str, int]
                ) -> mujoco.MjData:
    """``data`` when no entity sleeps; else a copy forwarded with sleeping off: MuJoCo
    finds no contacts for a sleeping body (against the static world or another sleeper),
    so a box asleep on the ground would have none. Its contacts are then those of the
    current positions (the bodies asleep have not moved since)."""
    bodies = np.fromiter(ids.values(), np.int64, len(ids))
    if not (data.body_awake[bodies] == mujoco.mjtSleepState.mjS_ASLEEP).any():
        return data
    scratch = mujoco.MjData(model)
    mujoco.mj_copyData(scratch, model, data)
    flag = int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    model.opt.enableflags &= ~flag
    try:
        mujoco.mj_forward(model, scratch)
    finally:
        model.opt.enableflags |= flag
    return scratch


def geom_entities(model: mujoco.MjModel, ids: Mapping[str, int]
                  ) -> tuple[list[str], np.ndarray]:
    """Entity names, and each geom's index into them (-1: no entity's, e.g. parked)."""
    names = list(ids)
    of_body = np.full(model.nbody, -1, np.int32)
    of_body[np.fromiter(ids.values(), np.int64, len(ids))] = np.arange(len(names))
    return names, of_body[model.geom_bodyid]


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


def contacts(model: mujoco.MjModel, data: mujoco.MjData, geom_label: np.ndarray,
             labels: Sequence[str], names: Sequence[str] | None
             ) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The last step's active contacts between entities (either among ``names`` when
    given): entities, positions, normals from the first to the second, normal forces,
    penetrations."""
    n = data.ncon
    pair = data.contact.geom[:n]
    first, second = geom_label[pair[:, 0]], geom_label[pair[:, 1]]
    keep = (data.contact.exclude[:n] == 0) & (first >= 0) & (second >= 0)
    if names is not None:
        index = {name: i for i, name in enumerate(labels)}
        wanted = np.zeros(len(labels), bool)
        wanted[[index[x] for x in names if x in index]] = True
        keep &= wanted[first] | wanted[second]
    rows = np.flatnonzero(keep)
    force = np.empty(6)
    forces = np.empty(len(rows))
    for k, i in enumerate(rows):
        mujoco.mj_contactForce(model, data, int(i), force)
        forces[k] = max(force[0], 0.0)
    return ([labels[j] for j in first[rows]], [labels[j] for j in second[rows]],
            data.contact.pos[rows].copy(), data.contact.frame[rows, :3].copy(), forces,
            np.maximum(-data.contact.dist[rows], 0.0))
