"""The contact points of a MuJoCo world's last step between entities, as the engine
contract has them (what the engine serves between steps is kept by ``observed``).

Only entities' geoms count: a parked body's geom (``parked``) is no entity's and is never
reported. A sleeping body's contacts are those of its current positions.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from galton.daemon.engines.mujoco.entities import geom_entities

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def touching(engine: MujocoEngine, names: Sequence[str] | None
             ) -> tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Engine.contacts: the last step's contacts (see ``contacts``)."""
    if names is not None:
        engine.body_ids(names)  # NotFoundError for a name that is no entity's
    m = engine.model
    labels, label = geom_entities(m, engine.ids)
    return contacts(m, _awake_view(m, engine.data, engine.ids), label, labels, names)


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
