"""Wrenches held on bodies of the MuJoCo world, through ``MjData.xfrc_applied``.

MuJoCo applies ``xfrc_applied`` (force, torque; world frame) at a body's centre of mass in
every step, and wakes a sleeping body it pushes. A wrench given at a point p is moved to the
centre of mass c taken at the time of the call (torque + (p - c) x force) and then held
constant. The books are kept by entity name and written again whole after every change of
the body ids (a compile, a delete), so a parked or removed body keeps no force.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import mujoco
import numpy as np


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
