"""What every law experiment needs: the engine's step and gravity, a seeded generator, and
a way to follow bodies or a joint through time with one round trip per sample."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from galton.analysis.laws import Check
from galton.client.sdk.client import Client
from galton.protocol import Capabilities

STANDARD_GRAVITY = 9.81  # m/s², assumed where an engine's world has no "gravity" parameter


@dataclass
class LawContext:
    """One engine's world, as the experiments see it."""

    engine: str
    capabilities: Capabilities
    timestep: float
    gravity: float  # m/s², pointing down (-z)
    rng: np.random.Generator

    def steps(self, seconds: float) -> int:
        """Whole steps covering ``seconds`` (at least one)."""
        return max(1, round(seconds / self.timestep))


@dataclass
class Trace:
    """Sampled states of named bodies: times (n,), poses (n, bodies, 7), twists (n, bodies, 6)."""

    times: np.ndarray
    poses: np.ndarray
    twists: np.ndarray


def trace(sim: Client, ctx: LawContext, names: Sequence[str], seconds: float,
          every: float) -> Trace:
    """The bodies' states now and every ``every`` s (rounded to whole steps) for
    ``seconds``: one step-and-read round trip per sample."""
    first = sim.get_states(names)
    times, poses, twists = [first.sim_time], [first.poses], [first.twists]
    stride = ctx.steps(every)
    for _ in range(max(1, round(seconds / (stride * ctx.timestep)))):
        states = sim.step_and_read(stride, names)
        times.append(states.sim_time)
        poses.append(states.poses)
        twists.append(states.twists)
    return Trace(np.array(times), np.array(poses), np.array(twists))


def joint_trace(sim: Client, ctx: LawContext, joint: str, seconds: float,
                every: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times, positions and velocities of one joint, now and every ``every`` s."""
    first = sim.get_joint_states([joint])
    times, angles, rates = [0.0], [first.positions[0]], [first.velocities[0]]
    stride = ctx.steps(every)
    for i in range(1, max(1, round(seconds / (stride * ctx.timestep))) + 1):
        states = sim.step_and_read_joints(stride, [joint])
        times.append(i * stride * ctx.timestep)
        angles.append(states.positions[0])
        rates.append(states.velocities[0])
    return np.array(times), np.array(angles, dtype=float), np.array(rates, dtype=float)


def unsupported(law: str, quantities: Sequence[tuple[str, str, float, float, str]],
                why: str) -> list[Check]:
    """The checks of a law the engine cannot run, each with no value and the reason."""
    return [Check(law, quantity, unit, theory, None, tolerance, reason, note=why)
            for quantity, unit, theory, tolerance, reason in quantities]
