"""What SDK calls return beyond the protocol's records: stamps and body states.

Each value is built from the reply that carried it, so a value never mixes one request's
numbers with another's (a Client may be used from several threads at once).
"""

from __future__ import annotations

from dataclasses import dataclass

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
