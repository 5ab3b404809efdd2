"""Wrenches held on bodies of the MuJoCo world, through ``MjData.xfrc_applied``.

MuJoCo applies ``xfrc_applied`` (force, torque; world frame) at a body's centre of mass in
every step, and wakes a sleeping body it pushes. A wrench given at a point p is moved to the
centre of mass c taken at the time of the call (torque + (p - c) x force) and then held
constant. The records are kept by entity name and written again whole after every change of
the body ids (a compile, a delete), so a parked or removed body keeps no force.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import mujoco
import numpy as np

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


class Wrenches:
    """The wrench (6,) held on each body, at its centre of mass, by entity name."""

    def __init__(self) -> None:
        self.held: dict[str, np.ndarray] = {}

    def hold(self, d: mujoco.MjData, names: Sequence[str], ids: np.ndarray,
             wrenches: np.ndarray, points: np.ndarray | None) -> None:
        at_com = np.array(wrenches, dtype=float, copy=True)
        if points is not None:
            arm = np.asarray(points, dtype=float) - d.xipos[ids]
            at_com[:, 3:] += np.cross(arm, at_com[:, :3])
        for row, name in enumerate(names):
            self.held[name] = at_com[row]

    def drop(self, names: Sequence[str] | None) -> None:
        if names is None:
            self.held.clear()
            return
        for name in names:
            self.held.pop(name, None)

    def apply(self, d: mujoco.MjData, ids: Mapping[str, int]) -> None:
        """Write the held wrenches into the data, zeros everywhere else."""
        d.xfrc_applied[:] = 0.0
        if self.held:
            rows = np.fromiter((ids[n] for n in self.held), dtype=np.int64,
                               count=len(self.held))
            d.xfrc_applied[rows] = np.array(list(self.held.values()))


def set_wrenches(engine: MujocoEngine, names: Sequence[str], wrenches: np.ndarray,
                 points: np.ndarray | None) -> None:
    """The centres of mass are computed from the current state (the data's were taken
    before the last step's integration)."""
    ids = engine.body_ids(names)
    if points is not None:
        mujoco.mj_kinematics(engine.model, engine.data)
    engine.wrenches.hold(engine.data, names, ids, wrenches, points)
    engine.wrenches.apply(engine.data, engine.ids)


def clear_wrenches(engine: MujocoEngine, names: Sequence[str] | None) -> None:
    """Drop the named bodies' wrenches (NotFoundError for an unknown name), or all."""
    if names is not None:
        engine.body_ids(names)
    engine.wrenches.drop(names)
    engine.wrenches.apply(engine.data, engine.ids)


def restore_joints(engine: MujocoEngine) -> None:
    """Every loaded model's joints back as loaded, no targets held, no wrenches."""
    joints = engine.loaded_joints
    roots = np.fromiter((engine.ids[n] for n in joints.infos), dtype=np.int64,
                        count=len(joints.infos))
    joints.restore(engine.model, engine.data, roots)
    engine.wrenches.drop(None)
    engine.wrenches.apply(engine.data, engine.ids)
