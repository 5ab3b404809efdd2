"""An ODE world's state kept in memory, for snapshots and restores of an unchanged structure
(daemon/world/states.py): every moving body's own doubles (position, rotation, velocities,
as ODE holds them), whether it is awake, the held wrenches and the joints' targets.

ODE keeps little else between steps: each step's contact joints are made anew, and the idle
counters of auto-disable are restarted on both sides (``reset_dynamics``, as the portable
snapshot does to its source), so a world set to a kept state goes on bit for bit as it went
on from the moment it was kept. The state fits only a world with the same moving bodies
(the World checks the structure; this refuses, False, what it can see
does not fit).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.ode.native import LIB
from galton.daemon.engines.ode.spawn import ASLEEP, AWAKE

if TYPE_CHECKING:
    from galton.daemon.engines.ode.engine import OdeEngine

# A joint's held target: mode, target, kp, kd, max_effort, effort, pushed.
JointTarget = tuple[str, float, float, float, float, float, float]


@dataclass(frozen=True)
class OdeState:
    """One moment of an ODE world (see the module docstring)."""

    names: tuple[str, ...]
    states: np.ndarray  # (moving bodies, ODE's doubles)
    awake: np.ndarray  # (moving bodies,) bool
    wrenches: dict[str, list[float]]
    joints: dict[str, JointTarget]
    diverged: bool
    nbytes: int


def save(engine: OdeEngine) -> OdeState:
    """The world's state now; its hidden counters restarted first (as a snapshot does)."""
    engine.reset_dynamics()
    moving = engine._moving
    states = np.array([b.state for b in moving]) if moving else np.zeros((0, 0))
    awake = np.array([b.awake for b in moving], dtype=bool)
    joints = {name: (j.info.mode, j.target, j.kp, j.kd, j.max_effort, j.effort, j.pushed)
              for name, j in engine._robots.by_name.items()}
    return OdeState(tuple(b.name for b in moving), states, awake,
                    {n: list(w) for n, w in engine._wrenches.items()}, joints,
                    engine._diverged, int(states.nbytes + awake.nbytes + 64 * len(joints)))


def load(engine: OdeEngine, state: Any) -> bool:
    """Set the world to ``state``; False (nothing changed) when it does not fit."""
    moving = engine._moving
    if not isinstance(state, OdeState) or len(state.names) != len(moving) or \
            set(state.joints) != set(engine._robots.by_name):
        return False
    rows = dict(zip(state.names, range(len(state.names)), strict=True))
    if any(b.name not in rows for b in moving):
        return False
    for body in moving:  # (a clone may hold them in another order)
        row, awake = state.states[rows[body.name]], state.awake[rows[body.name]]
        LIB.dBodySetPosition(body.body, *row[:3])  # marks the geoms moved
        body.state[:] = row
        body.awake = bool(awake)
        body.set_bits(AWAKE if awake else ASLEEP)
    _wrenches(engine, state.wrenches)
    for name, (mode, target, kp, kd, max_effort, effort, pushed) in state.joints.items():
        joint = engine._robots.by_name[name]
        joint.info.mode = mode
        joint.target, joint.kp, joint.kd = target, kp, kd
        joint.max_effort, joint.effort, joint.pushed = max_effort, effort, pushed
        if joint.scalar:
            velocity = target if mode == "velocity" else 0.0
            damping = kd if mode in ("position", "velocity") else 0.0
            joint.motor(velocity, damping, np.inf if mode == "position" else max_effort)
    engine.reset_dynamics()  # every body enabled as kept, its idle counters restarted
    engine._diverged = state.diverged
    return True


def _wrenches(engine: OdeEngine, kept: dict[str, list[float]]) -> None:
    """The held wrenches as kept, each held body kept awake (as set_wrenches does)."""
    for name in engine._wrenches:
        if name not in kept and name in engine._bodies:
            LIB.dBodySetAutoDisableDefaults(engine._bodies[name].body)
    engine._wrenches = {n: list(w) for n, w in kept.items()}
    for name in kept:
        LIB.dBodySetAutoDisableFlag(engine._bodies[name].body, 0)
