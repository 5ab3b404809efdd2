"""The one seam through which calibrate evaluates its candidates: each candidate is a set
of parameter values; its error is how far a prediction from the start, with those values,
lands from what was observed. A batch of candidates (a generation of the search) runs as
one set of futures of the start world (daemon/world/futures.py): one fork per candidate,
its body properties set by the future's overrides and a world parameter (gravity) by its
start action (each fork has its own model, so per-future gravity is safe), all stepped
together (MuJoCo's on ``future_threads`` native threads). The live world is never touched.

``CandidateBatch`` is the batch in chunks, so the live world keeps its clock: one fork per
``advance`` while it is being made, then a chunk of every future's steps sized to about
``CHUNK_WALL_S`` of work; ``evaluate_candidates`` runs a whole batch at once."""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from galton.daemon.core.calls import smoothed_step_cost
from galton.daemon.core.fit_params import (
    DAMPING,
    GRAVITY,
    Parameter,
    apply_values,
    body_properties,
)
from galton.daemon.core.limits import Limits
from galton.daemon.world.futures import FutureSet, FutureSpec
from galton.daemon.world.world import World
from galton.protocol import PhysicsError

CHUNK_WALL_S = 0.002  # as a prediction's chunk (daemon/core/side_jobs.py)
WORLD_SET = (GRAVITY, DAMPING)  # set on each fork by its start, not as body overrides


@dataclass(frozen=True)
class Observation:
    """Where the observed bodies were seen: ``steps`` after the start (increasing, > 0) and
    their positions then, (samples, bodies, 3), NaN where a body was not seen."""

    names: list[str]
    steps: np.ndarray
    positions: np.ndarray

    @property
    def horizon(self) -> int:
        return int(self.steps[-1]) if len(self.steps) else 0


def future_spec(params: Sequence[Parameter], values: Mapping[str, float]) -> FutureSpec:
    """A candidate as a future: its body values as overrides, gravity and joints' damping
    as its start."""
    overrides = [(list(p.bodies), body_properties(p.prop, values[p.name]))
                 for p in params if p.prop not in WORLD_SET]
    world_params = [p for p in params if p.prop in WORLD_SET]
    start = None
    if world_params:
        def start(world: World) -> None:
            apply_values(world, world_params, values)
    return FutureSpec(start=start, overrides=overrides)


class CandidateBatch:
    """Candidates evaluated as one set of futures, a chunk at a time (module docstring).
    ``errors`` holds each candidate's position error once ``finished`` (inf: diverged)."""

    def __init__(self, start: World, params: Sequence[Parameter],
                 candidates: Sequence[Mapping[str, float]], observation: Observation,
                 limits: Limits, step_cost: float = 1e-5) -> None:
        self.start, self.seen, self.limits = start, observation, limits
        self.candidates = [dict(values) for values in candidates]
        self.specs = [future_spec(params, values) for values in candidates]
        self.rows = np.full((len(candidates), *observation.positions.shape), np.nan)
        self.errors = np.full(len(candidates), math.inf)
        self.parts: list[FutureSet] = []
        self.futures: FutureSet | None = None
        self.alive: list[int] = []  # the candidate each future of ``futures`` is
        self.sample = 0  # the next observed sample
        self.step_cost = step_cost  # seconds per future's step, sizing the chunks

    def __len__(self) -> int:
        return len(self.candidates)

    @property
    def finished(self) -> bool:
        return self.futures is not None and (not self.alive
                                             or self.sample == len(self.seen.steps))

    def advance(self) -> int:
        """One chunk: a fork while the futures are being made, then steps of all of them;
        returns the steps taken (all futures together)."""
        if self.futures is None:
            self._fork_next()
            return 0
        target = int(self.seen.steps[self.sample])
        count = min(target - self.futures.done,
                    max(1, int(CHUNK_WALL_S / (self.step_cost * len(self.alive)))))
        began = time.perf_counter()
        self.futures.step(count)
        self.step_cost = smoothed_step_cost(self.step_cost, time.perf_counter() - began,
                                            count * len(self.alive))
        taken = count * len(self.alive)
        if self.futures.done == target:
            self._take_sample()
        if self.finished:
            self._score()
        return taken

    def run(self) -> np.ndarray:
        """The whole batch at once: each candidate's error."""
        try:
            while not self.finished:
                self.advance()
        finally:
            self.close()
        return self.errors

    def close(self) -> None:
        for part in self.parts:
            part.close()
        self.parts = []
        if self.futures is not None:
            self.futures.close()

    def _fork_next(self) -> None:
        index = len(self.parts)
        if index < len(self.specs):
            self.parts.append(FutureSet.fork(self.start, [self.specs[index]], self.limits))
        if len(self.parts) < len(self.specs):
            return
        worlds = [w for part in self.parts for w in part.worlds]
        events = [e for part in self.parts for e in part.events]
        self.parts = []
        self.futures = FutureSet(worlds, events, self.limits.future_threads
                                 if len(worlds) > 1 else 1)
        self.alive = list(range(len(worlds)))
        if not self.seen.steps.size:
            self._score()

    def _take_sample(self) -> None:
        """Each future's observed positions now; a diverged one is dropped (error inf)."""
        assert self.futures is not None
        for position, world in reversed(list(enumerate(self.futures.worlds))):
            try:
                world.verify()
            except PhysicsError:
                world.engine.close()
                del self.futures.worlds[position], self.futures.events[position]
                del self.alive[position]
        if self.alive:
            where = self.futures.positions(self.seen.names)
            self.rows[self.alive, self.sample] = where
        self.sample += 1

    def _score(self) -> None:
        for index in self.alive:
            self.errors[index] = position_error(self.rows[index], self.seen.positions)


def evaluate_candidates(start: World, params: Sequence[Parameter],
                        candidates: Sequence[Mapping[str, float]], observation: Observation,
                        limits: Limits) -> np.ndarray:
    """Each candidate's position error (m): the mean distance, over the observed bodies and
    samples, between where a prediction from ``start`` with the candidate's values puts
    each body and where it was seen. ``start`` itself is left as it was."""
    return CandidateBatch(start, params, candidates, observation, limits).run()


def position_error(predicted: np.ndarray, observed: np.ndarray) -> float:
    """The mean distance over the (sample, body) pairs that were seen."""
    distances = np.linalg.norm(predicted - observed, axis=-1)
    seen = np.isfinite(distances)
    return float(distances[seen].mean()) if seen.any() else 0.0
