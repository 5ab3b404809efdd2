"""What the last step left to observe (contacts, joint efforts), kept until the next step.

MuJoCo recomputes contacts and actuator forces whenever its data is forwarded or
recompiled: a spawn, a delete or a teleport between two steps would change what
``contacts`` and ``get_joint_states`` report although nothing stepped (issue 35). So the
engine freezes them before the first such edit after a step, and serves the frozen copy
until the next step (dropping what involves entities deleted meanwhile).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.mujoco import contacts as touches

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

ContactRows = tuple[list[str], list[str], np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@dataclass(frozen=True)
class Observed:
    """The last step's contacts (all of them) and each held joint's effort."""

    contacts: ContactRows
    efforts: dict[str, float]


def freeze(engine: MujocoEngine) -> None:
    """Keep what the last step left, before an edit recomputes it (once per step)."""
    if engine.observed is not None:
        return
    names = [j.name for j in engine.loaded_joints.describe() if j.scalar]
    efforts = engine.loaded_joints.read(engine.data, names)[2] if names else np.zeros(0)
    engine.observed = Observed(touches.touching(engine, None),
                                dict(zip(names, efforts.tolist(), strict=True)))


def contacts(engine: MujocoEngine, names: Sequence[str] | None) -> ContactRows:
    """The last step's contacts among entities still there (either among ``names``)."""
    observed = engine.observed
    if observed is None:
        return touches.touching(engine, names)
    if names is not None:
        engine.body_ids(names)  # NotFoundError for a name that is no entity's
    first, second, positions, normals, forces, depths = observed.contacts
    wanted = None if names is None else set(names)
    rows = [i for i, (a, b) in enumerate(zip(first, second, strict=True))
            if a in engine.ids and b in engine.ids
            and (wanted is None or a in wanted or b in wanted)]
    return ([first[i] for i in rows], [second[i] for i in rows], positions[rows],
            normals[rows], forces[rows], depths[rows])


def efforts(engine: MujocoEngine, names: Sequence[str], current: np.ndarray) -> np.ndarray:
    """The efforts of the last step (a joint loaded since: none yet, 0)."""
    observed = engine.observed
    if observed is None:
        return current
    return np.array([observed.efforts.get(n, 0.0) for n in names], dtype=float)
