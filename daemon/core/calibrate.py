"""calibrate: fit parameters (friction, restitution, mass, gravity) so that a prediction
from the observation's start matches what was observed, and with ``apply`` set them in the
world. A population search (daemon/core/cmaes.py) asks for candidates; each is evaluated
through the one seam, daemon/core/candidates.py, as a batch of futures (one per candidate,
a generation at a time) run as a side job between the live world's steps, in chunks of
about a prediction's chunk of work; a progress event per generation, ended by ``pause`` as
a prediction is. The live world is changed only by ``apply``, at the end."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from galton.daemon.core.calls import Call, StepJob
from galton.daemon.core.candidates import CandidateBatch, Observation
from galton.daemon.core.cmaes import CmaEs, default_population
from galton.daemon.core.context import PredictContext
from galton.daemon.core.fit_params import Parameter, apply_values, current_values, parameters
from galton.daemon.core.limits import Limits
from galton.daemon.core.observations import (
    observation,
    sample_poses,
    sample_times,
    start_twists,
)
from galton.daemon.world.snapshot import clone_of, decode, world_from
from galton.daemon.world.world import World
from galton.protocol import (
    IncorrectStateError,
    InvalidArgumentError,
    OperationFailedError,
)
from galton.protocol.model import check_names, decode_twists
from galton.protocol.operations import Calibrate

START_SIGMA = 0.3  # the search's largest first step, in units of each parameter's range
# Before the search, a Latin hypercube of this many populations' worth of candidates over
# the bounds: contact makes error landscapes rugged (a box that tips over at high friction
# slides as far as one at low), and a search started only from the world's own values
# can settle in the wrong valley; it starts from the design's best instead.
DESIGN_PER_POPULATION = 2
MIN_DESIGN_SIGMA = 0.05
PERFECT = 1e-12  # m: an error this small cannot be bettered


class Calibration:
    """A calibration in progress: the search, the best candidate so far, what it cost."""

    def __init__(self, start: World, params: list[Parameter], seen: Observation,
                 limits: Limits, request: Calibrate) -> None:
        self.start, self.params, self.seen, self.limits = start, params, seen, limits
        self.before = current_values(start, params)
        mean = np.array([p.to_unit(np.clip(self.before[p.name], p.low, p.high))
                         for p in params])
        self.population = request.population or default_population(len(params))
        self.rng = np.random.default_rng(request.seed)
        self.search = CmaEs(mean, START_SIGMA, self.population, self.rng)
        self.design: list[np.ndarray] = list(latin_hypercube(
            DESIGN_PER_POPULATION * self.population, len(params), self.rng))
        self.max_predictions = request.max_predictions
        self.predictions = 0
        self.error_before = float("nan")
        self.best: dict[str, float] = {p.name: p.from_unit(u) for p, u in
                                       zip(params, mean, strict=True)}
        self.best_error = float("inf")
        self.pending: list[np.ndarray] = []
        self.generation: list[np.ndarray] = []  # the search's candidates being evaluated
        self.batch: CandidateBatch | None = None
        self.batches = 0  # batches of futures run
        self.step_cost = 1e-5  # seconds per future's step, sizing the chunks
        self.emit: Callable[[dict[str, Any]], None] = lambda event: None
        self.on_result: Callable[[dict[str, float]], bool] = lambda values: False

    def values(self, unit: np.ndarray) -> dict[str, float]:
        return {p.name: p.from_unit(float(u)) for p, u in zip(self.params, unit, strict=True)}

    def advance(self) -> int:
        """One chunk of the current batch of candidates (a new batch when none is running:
        the world's own values with the design, then each generation of the search);
        returns the steps it took, all futures together."""
        if self.batch is None:
            self.batch = self._next_batch()
        steps = self.batch.advance()
        if self.batch.finished:
            batch, self.batch = self.batch, None
            batch.close()
            self.step_cost = batch.step_cost
            self._told(batch)
        return steps

    def close(self) -> None:
        """Close the running batch's futures (the job ended before it did)."""
        if self.batch is not None:
            self.batch.close()
            self.batch = None

    def _next_batch(self) -> CandidateBatch:
        """The next candidates, as many as the budget of predictions still allows."""
        room = self.max_predictions - self.predictions
        if self.predictions == 0:  # the world's own values (the error before), the design
            units = self.design[::-1][:room - 1]
            self.design = self.design[:len(self.design) - len(units)]
            candidates = [self.before, *(self.values(u) for u in units)]
        else:  # (a design cut short by the budget ended the search)
            if not self.pending:
                self.pending = list(self.search.ask())
            taken, self.pending = self.pending[:room], self.pending[room:]
            self.generation = taken
            candidates = [self.values(u) for u in taken]
        self.batches += 1
        return CandidateBatch(self.start, self.params, candidates, self.seen, self.limits,
                              self.step_cost)

    def _told(self, batch: CandidateBatch) -> None:
        """A batch's errors: the best so far kept (a value outside its bounds, as the
        world's own may be, is never the fit); a whole generation told to the search."""
        first = self.predictions == 0
        for values, error in zip(batch.candidates, batch.errors, strict=True):
            inside = all(p.low <= values[p.name] <= p.high for p in self.params)
            if error < self.best_error and inside:
                self.best, self.best_error = dict(values), float(error)
        self.predictions += len(batch)
        if first:
            self.error_before = float(batch.errors[0])
            if not self.design:
                self._start_search()
            return
        if not self.pending and len(self.generation) == self.population:
            self.search.tell(np.array(self.generation), np.asarray(batch.errors))
            self.generation = []
            self.emit({"kind": "calibration", "generation": self.search.generation,
                       "predictions": self.predictions, "best_error": self.best_error,
                       "spread": self.search.spread})

    def _start_search(self) -> None:
        """After the design: CMA-ES from its best point, a few design cells wide."""
        best = np.array([p.to_unit(self.best[p.name]) for p in self.params])
        sigma = min(START_SIGMA, max(MIN_DESIGN_SIGMA, 2.0 / (DESIGN_PER_POPULATION
                                                              * self.population)))
        self.search = CmaEs(best, sigma, self.population, self.rng)
        self.emit({"kind": "calibration", "generation": 0, "predictions": self.predictions,
                   "best_error": self.best_error, "spread": self.search.spread})

    @property
    def finished(self) -> bool:
        return (self.predictions >= self.max_predictions or self.search.converged
                or self.best_error <= PERFECT)

    def intervals(self) -> dict[str, list[float]]:
        """Each value's range over the search's last selected candidates, and the fit;
        before the search's first generation, its bounds (nothing narrower is known)."""
        if self.search.generation == 0:
            return {p.name: [p.low, p.high] for p in self.params}
        selected = [self.values(unit) for unit in self.search.selected]
        return {p.name: [min(self.best[p.name], *(s[p.name] for s in selected)),
                         max(self.best[p.name], *(s[p.name] for s in selected))]
                for p in self.params}

    def result(self) -> dict[str, Any]:
        applied = self.on_result(self.best)
        return {"fitted": self.best, "intervals": self.intervals(),
                "error_before": self.error_before, "error_after": self.best_error,
                "predictions": self.predictions, "generations": self.search.generation,
                "steps": self.predictions * self.seen.horizon,
                "converged": self.search.converged or self.best_error <= PERFECT,
                "applied": applied, "batches": self.batches}


def latin_hypercube(count: int, dimensions: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` points in the unit box, one in each of ``count`` slices of every axis."""
    cells = np.array([rng.permutation(count) for _ in range(dimensions)]).T
    points: np.ndarray = (cells + rng.random((count, dimensions))) / count
    return points


def calibrate(ctx: PredictContext, call: Call, request: Calibrate) -> None:
    """Start a calibration job (answered when its search ends)."""
    if ctx.job is not None:
        raise IncorrectStateError("another step request is still running; wait for it")
    if ctx.engine_factory is None:
        raise OperationFailedError("this daemon cannot make engines")
    source = ctx.world_for(request)
    names = check_names(request.names, "calibrate.names")
    times = sample_times(request.times)
    poses = sample_poses(request.poses, len(times), len(names))
    start = _start(ctx, source, request, names, times, poses)
    try:
        run = _calibration(ctx, start, request, names, times, poses)
    except Exception:
        start.engine.close()
        raise
    run.emit = lambda event: ctx.emit({**event, "world": source.name})
    if request.apply:
        run.on_result = lambda values: _apply(ctx, source, run.params, values)
    total = run.max_predictions * run.seen.horizon
    job = StepJob(call, total, total, world=start, scratch=True, driver=run)
    job.source = source
    ctx.start_job(job)


def _calibration(ctx: PredictContext, start: World, request: Calibrate, names: list[str],
                 times: np.ndarray, poses: np.ndarray) -> Calibration:
    start.require_known(names)
    params = parameters(start, request.fit)
    seen = observation(names, times, poses, start.engine.timestep)
    limit = ctx.limits.max_steps  # the whole search's steps, as one step request's
    if seen.horizon * request.max_predictions > limit:
        raise InvalidArgumentError(
            f"calibrate: {request.max_predictions} predictions of {seen.horizon} steps "
            f"would take {seen.horizon * request.max_predictions} steps; at most {limit} "
            "(ask for fewer max_predictions, or observe a shorter time)",
            {"max_steps": limit})
    return Calibration(start, params, seen, ctx.limits, request)


def _start(ctx: PredictContext, source: World, request: Calibrate, names: list[str],
           times: np.ndarray, poses: np.ndarray) -> World:
    """The world every candidate starts from: a snapshot slot's, or a copy of ``source``
    with the observed bodies set to the first sample (and its twists)."""
    name = f"{source.name}:calibration"
    if request.slot is not None:  # a slot kept in memory has no blob: its twin's copy
        factory = ctx.engine_factory
        assert factory is not None
        return ctx.slots.world_of(ctx.slots.get(request.slot), name, lambda blob: world_from(
            decode(blob, ctx.limits, ctx.snapshot_key), factory, name, ctx.limits))
    source.require_known(names)
    source.require_no_links(names, "calibrate.names", "a link moves with its joints, so the "
                            "start cannot set it: observe the model's root")
    twists = (start_twists(times, poses, source.engine.timestep) if request.twists is None
              else decode_twists(request.twists, len(names), "calibrate.twists"))
    source.verify()
    copy = clone_of(source, name, ctx.limits)
    try:
        copy.set_states(names, poses[0].copy(), twists)
    except Exception:
        copy.engine.close()
        raise
    return copy


def _apply(ctx: PredictContext, world: World, params: list[Parameter],
           values: dict[str, float]) -> bool:
    apply_values(world, params, values)
    ctx.emit({"kind": "scene", "op": "calibrate", "world": world.name,
               "step": world.step_index})
    return True
