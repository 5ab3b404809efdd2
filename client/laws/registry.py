"""The suite's experiments by key, in the order they run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Union

import numpy as np

from galton.analysis.laws import Check
from galton.client.laws import bodies, contact, motion
from galton.client.laws.context import LawContext
from galton.client.sdk.client import Client

Outcome = Union[list[Check], tuple[list[Check], dict[str, np.ndarray]]]  # noqa: UP007


@dataclass(frozen=True)
class Experiment:
    """One law: its key, the sentence a report shows, and the run (on an empty world)."""

    key: str
    law: str
    run: Callable[[Client, LawContext], Outcome]


EXPERIMENTS: tuple[Experiment, ...] = (
    Experiment("free-fall", "free fall: z0 − g t²/2", motion.free_fall),
    Experiment("projectile", "projectile: x = vx t, z = vz t − g t²/2", motion.projectile),
    Experiment("pendulum-small", "pendulum, small amplitude: 2π√(I/mgd)",
               motion.pendulum_small),
    Experiment("pendulum-large", "pendulum at π/2: 4√(I/mgd) K(sin θ₀/2); energy kept",
               motion.pendulum_large),
    Experiment("rolling-sphere", "sphere rolling down an incline: 5/7 g sin θ",
               contact.rolling_sphere),
    Experiment("rolling-cylinder", "cylinder rolling down an incline: 2/3 g sin θ",
               contact.rolling_cylinder),
    Experiment("block-incline", "block on an incline: holds if tan θ ≤ μ, else "
               "g (sin θ − μ cos θ)", contact.block_incline),
    Experiment("puck", "puck sliding to rest: v²/(2 μ g)", contact.puck),
    Experiment("rebound", "ball rebound: e² h", contact.rebound),
    Experiment("two-spheres", "two-sphere collision: momentum kept, separation e × approach",
               bodies.two_spheres),
    Experiment("cradle", "Newton's cradle: one in, one out", bodies.cradle),
    Experiment("tower", "ten-box tower stands 10 s", bodies.tower),
    Experiment("torque-free", "torque-free asymmetric body: L kept, intermediate axis flips",
               bodies.torque_free),
)
KEYS = tuple(e.key for e in EXPERIMENTS)
BY_KEY = {e.key: e for e in EXPERIMENTS}
