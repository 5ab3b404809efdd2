"""Many futures of one world, stepped together: each a fork of the world (sharing its
structure), started from its own perturbed state, given its own body properties and its
own timed actions, so that one prediction imagines N alternatives.

The seam (used by ``predict``, and by anything that imagines candidates):
``FutureSet.fork(world, specs, limits, threads)`` with one ``FutureSpec`` per future:
``start`` (called once on the fork: set states, perturb), ``overrides`` (body properties
set on the fork before it starts: a calibration's candidate masses, frictions,
restitutions) and ``events`` (actions at whole steps from the start). ``step(count)``
advances every future by ``count`` steps, cut where an event falls, so an action lands on
the same step however the steps are grouped (as a live plan's would); futures of an engine
that releases the GIL while stepping (MuJoCo) are stepped on ``threads`` native threads at
once, the others one after another.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from galton.daemon.core.limits import Limits
from galton.daemon.world.snapshot import clone_of
from galton.daemon.world.world import World
from galton.protocol import BodyProperties

Action = Callable[[World], None]


@dataclass
class FutureSpec:
    """How one future differs from the world it forks (see the module docstring)."""

    start: Action | None = None
    overrides: Sequence[tuple[Sequence[str], BodyProperties]] = ()
    events: Sequence[tuple[int, Action]] = ()  # (step from the start, action)


@dataclass
class FutureSet:
    """N futures stepped together; closed (every fork's engine) by ``close``."""

    worlds: list[World]
    events: list[list[tuple[int, Action]]]
    threads: int = 1
    done: int = 0
    _pool: ThreadPoolExecutor | None = field(default=None, repr=False)

    @classmethod
    def fork(cls, world: World, specs: Sequence[FutureSpec], limits: Limits,
             threads: int = 1, first: World | None = None) -> FutureSet:
        """One fork of ``world`` per spec (``first``, a fork already made, serves the
        first), each started as its spec says; every fork closed again if one fails."""
        worlds: list[World] = []
        try:
            for index in range(len(specs)):  # every fork before any is changed
                worlds.append(first if index == 0 and first is not None else clone_of(
                    world, f"{world.name}:future{index}", limits))
            for fork, spec in zip(worlds, specs, strict=True):
                for names, props in spec.overrides:
                    fork.update(names, props)
                if spec.start is not None:
                    spec.start(fork)
        except Exception:
            for made in worlds:
                if made is not first:
                    made.engine.close()
            raise
        events = [sorted(spec.events, key=lambda e: e[0]) for spec in specs]
        futures = cls(worlds, events, threads if len(worlds) > 1 else 1)
        futures._act(0)
        return futures

    def __len__(self) -> int:
        return len(self.worlds)

    def step(self, count: int) -> None:
        """``count`` steps of every future, each timed action at its step."""
        while count > 0:
            run = min(count, self._steps_to_next_event())
            self._step_all(run)
            self.done += run
            count -= run
            self._act(self.done)

    def verify(self) -> None:
        for world in self.worlds:
            world.verify()

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        for world in self.worlds:
            world.engine.close()

    def positions(self, names: Sequence[str]) -> np.ndarray:
        """(futures, bodies, 3) positions now."""
        return np.stack([w.get_states(names)[0][:, :3] for w in self.worlds])

    def _steps_to_next_event(self) -> int:
        later = [step for events in self.events for step, _ in events if step > self.done]
        return min(later) - self.done if later else 1 << 62

    def _act(self, step: int) -> None:
        for world, events in zip(self.worlds, self.events, strict=True):
            for at, action in events:
                if at == step:
                    action(world)

    def _step_all(self, count: int) -> None:
        parallel = self.threads > 1 and self.worlds[0].engine.releases_gil_while_stepping
        if not parallel:
            for world in self.worlds:
                world.step(count)
            return
        if self._pool is None:
            self._pool = ThreadPoolExecutor(self.threads, thread_name_prefix="galton-future")
        groups = [self.worlds[k::self.threads] for k in range(self.threads)]
        for done in [self._pool.submit(_step_each, group, count) for group in groups
                     if group]:
            done.result()


def _step_each(worlds: Sequence[World], count: int) -> None:
    """One thread's share of the futures (one hand-off per thread, not per future)."""
    for world in worlds:
        world.step(count)


def spread(positions: np.ndarray) -> np.ndarray:
    """Per body, the standard deviation of position across futures: the root mean square
    distance of each future's position from their mean (futures, bodies, 3) -> (bodies,)."""
    relative = positions - positions[0]  # exact zeros for identical futures
    offsets = relative - relative.mean(axis=0)
    result: np.ndarray = np.sqrt((offsets ** 2).sum(axis=2).mean(axis=0))
    return result
