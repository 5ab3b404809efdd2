"""What SDK calls return beyond the protocol's records: stamps, body and joint states.

Each value is built from the reply that carried it, so a value never mixes one request's
numbers with another's (a Client may be used from several threads at once).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from galton.protocol import POSE_WIDTH, TWIST_WIDTH, Reply, unpack_f64

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Stamp:
    """The step and sim time at which a request took effect (every reply carries them)."""

    step: int
    sim_time: float

    @classmethod
    def of(cls, reply: Reply) -> Stamp:
        return cls(reply.step, reply.sim_time)


@dataclass
class States:
    """Poses (n, 7: x y z qx qy qz qw) and world twists (n, 6) of named bodies, at the step
    and sim time of the reply that carried them."""

    names: list[str]
    poses: FloatArray
    twists: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> States:
        """The states a ``get_states`` or reading step reply holds, stamped by it."""
        result = reply.result
        return cls(list(result["names"]), unpack_f64(result["poses"], POSE_WIDTH, "poses"),
                   unpack_f64(result["twists"], TWIST_WIDTH, "twists"), reply.step,
                   reply.sim_time)

    @property
    def stamp(self) -> Stamp:
        return Stamp(self.step, self.sim_time)

    @property
    def positions(self) -> FloatArray:
        return self.poses[:, :3]

    @property
    def speeds(self) -> FloatArray:
        return np.asarray(np.linalg.norm(self.twists[:, :3], axis=1), dtype=np.float64)


@dataclass
class JointStates:
    """Positions, velocities and efforts (each (n,) float64) of named one-degree-of-freedom
    joints, at the step and sim time of the reply that carried them. Units: rad, rad/s,
    N·m for revolute joints; m, m/s, N for prismatic ones. ``efforts`` is what each joint's
    target applied in the last step (0 in mode "none")."""

    names: list[str]
    positions: FloatArray
    velocities: FloatArray
    efforts: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> JointStates:
        """The joint states of a ``get_joint_states`` reply."""
        return cls.from_result(reply.result, reply)

    @classmethod
    def from_step_reply(cls, reply: Reply) -> JointStates:
        """The joint states a ``step`` or ``run_until`` with ``read_joints`` carries."""
        return cls.from_result(reply.result["joints"], reply)

    @classmethod
    def from_result(cls, result: dict[str, Any], reply: Reply) -> JointStates:
        return cls(list(result["names"]), _column(result, "positions"),
                   _column(result, "velocities"), _column(result, "efforts"), reply.step,
                   reply.sim_time)

    @property
    def stamp(self) -> Stamp:
        return Stamp(self.step, self.sim_time)

    def __len__(self) -> int:
        return len(self.names)


def _column(result: dict[str, Any], key: str) -> FloatArray:
    return unpack_f64(result[key], 1, key)[:, 0]
