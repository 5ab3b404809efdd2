"""Wrenches held on bodies: which body holds one, and the step at which it ends.

The engine applies a held wrench every step; a wrench given a duration ends after a whole
number of steps (the duration rounded to steps, at least one), and the World runs its
steps in chunks that end exactly there, so the end never depends on how requests group
the steps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from galton.daemon.engines.base import Engine
from galton.protocol import InvalidArgumentError


class WrenchSchedule:
    """Bodies holding a wrench, each with the step index at which it ends (None: held
    until cleared)."""

    def __init__(self) -> None:
        self.ends: dict[str, int | None] = {}

    def apply(self, engine: Engine, names: Sequence[str], wrenches: np.ndarray,
              points: np.ndarray | None, duration: float | None, step_index: int) -> None:
        end = None if duration is None else step_index + steps_for(duration, engine.timestep)
        engine.set_wrenches(names, wrenches, points)
        for name in names:
            self.ends[name] = end

    def clear(self, engine: Engine, names: Sequence[str] | None) -> None:
        engine.clear_wrenches(names)
        if names is None:
            self.ends.clear()
        for name in names or ():
            self.ends.pop(name, None)

    def forget(self, names: Sequence[str]) -> None:
        """Bodies that are gone (their wrenches went with them)."""
        for name in names:
            self.ends.pop(name, None)

    def rewind(self, steps: int) -> None:
        """The step counter went back ``steps``: each end goes back with it, so a held
        wrench still lasts the steps it has left."""
        self.ends = {name: None if end is None else end - steps
                     for name, end in self.ends.items()}

    def steps_to_next_end(self, step_index: int) -> int | None:
        ends = [end for end in self.ends.values() if end is not None]
        return min(ends) - step_index if ends else None

    def expire(self, engine: Engine, step_index: int) -> None:
        ended = [name for name, end in self.ends.items() if end is not None and end <= step_index]
        if ended:
            self.clear(engine, ended)


# A duration longer than this many steps is refused (it would overflow an int's rounding).
MAX_WRENCH_STEPS = 1e15


def steps_for(duration: float, timestep: float) -> int:
    """A wrench's duration as whole steps: rounded, at least one."""
    if not math.isfinite(duration) or duration <= 0:
        raise InvalidArgumentError(f"apply_wrench.duration must be a number of seconds > 0, "
                                   f"got {duration}")
    steps = duration / timestep
    if steps > MAX_WRENCH_STEPS:
        raise InvalidArgumentError(
            f"apply_wrench.duration {duration:g} s is {steps:.3g} steps; at most "
            f"{MAX_WRENCH_STEPS:g} (leave duration out to hold the wrench until cleared)",
            {"max_steps": MAX_WRENCH_STEPS})
    return max(1, round(steps))
