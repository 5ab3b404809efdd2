"""A DART world's state kept in memory, for snapshots and restores of an unchanged
structure (daemon/world/states.py): each skeleton's generalized positions and velocities
(``Skeleton.getPositions``/``getVelocities``, the float64 numbers DART holds), the time,
and the held targets, efforts and wrenches.

DART keeps no contact state between steps; what makes a run depend on its history is the
order its collision detector holds the skeletons in, so both the keeping and the loading
rebuild the world (``_rebuild``, as a canonical snapshot does): then a world set to a kept
state is a world made afresh in the same order, and goes on bit for bit as it went on from
the moment it was kept. Cheaper than the portable restore, which makes every skeleton
anew; not free (a rebuild adds every skeleton to a new world).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.base import Target

if TYPE_CHECKING:
    from galton.daemon.engines.dart.engine import DartEngine


@dataclass(frozen=True)
class DartState:
    """One moment of a DART world (see the module docstring)."""

    owners: tuple[str, ...]
    positions: tuple[np.ndarray, ...]
    velocities: tuple[np.ndarray, ...]
    time: float
    targets: dict[str, Target]
    efforts: dict[str, float]
    wrenches: dict[str, tuple[Any, np.ndarray, np.ndarray]]
    diverged: bool
    nbytes: int


def save(engine: DartEngine) -> DartState:
    """The world's state now, after a rebuild (as a snapshot takes it)."""
    engine._rebuild()
    skeletons = [engine._bodies[o].skeleton for o in engine._owners]
    positions = tuple(np.array(s.getPositions(), dtype=float) for s in skeletons)
    velocities = tuple(np.array(s.getVelocities(), dtype=float) for s in skeletons)
    robots = engine._robots
    return DartState(tuple(engine._owners), positions, velocities,
                     float(engine._world.getTime()), dict(robots.targets),
                     dict(robots.efforts),
                     {n: (node, f.copy(), t.copy()) for n, (node, f, t)
                      in robots.wrenches.items()},
                     engine._diverged,
                     int(sum(p.nbytes + v.nbytes for p, v in zip(positions, velocities,
                                                                   strict=True))))


def load(engine: DartEngine, state: Any) -> bool:
    """Set the world to ``state``; False (nothing changed) when it does not fit."""
    if not isinstance(state, DartState) or tuple(engine._owners) != state.owners or \
            any(n not in engine._bodies for n in state.wrenches) or \
            any(n not in engine._robots.joints for n in state.targets):
        return False
    skeletons = [engine._bodies[o].skeleton for o in engine._owners]
    if any(s.getNumDofs() != len(p) for s, p in zip(skeletons, state.positions, strict=True)):
        return False
    for skeleton, p, v in zip(skeletons, state.positions, state.velocities, strict=True):
        skeleton.setPositions(p)
        skeleton.setVelocities(v)
    engine._rebuild()
    engine._world.setTime(state.time)
    robots = engine._robots
    robots.targets = dict(state.targets)
    robots.efforts = dict(state.efforts)
    robots.wrenches = {n: (engine._bodies[n].node, f.copy(), t.copy())
                       for n, (_, f, t) in state.wrenches.items()}
    engine._diverged = state.diverged
    engine._unchecked = True
    return True
