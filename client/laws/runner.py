"""Run the law suite through a daemon: every chosen experiment on a fresh world of every
chosen engine, collected as ``LawResults``."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from galton.analysis.laws import Check, EngineLaws, LawResults
from galton.client.laws.context import STANDARD_GRAVITY, LawContext
from galton.client.laws.registry import BY_KEY, EXPERIMENTS, KEYS, Experiment
from galton.client.sdk.client import Client
from galton.protocol import GaltonError, InvalidArgumentError

Progress = Callable[[str, str], None]  # (engine, experiment key), called before each run


def choose(only: Sequence[str] | None) -> list[Experiment]:
    """The experiments named in ``only`` (all when None), in the suite's order."""
    if not only:
        return list(EXPERIMENTS)
    unknown = [key for key in only if key not in BY_KEY]
    if unknown:
        raise InvalidArgumentError(f"unknown law(s) {', '.join(unknown)}: the suite has "
                                   f"{', '.join(KEYS)}")
    return [e for e in EXPERIMENTS if e.key in only]


def engines_of(sim: Client, wanted: Sequence[str] | None) -> list[str]:
    """The engines this daemon offers (all of them when ``wanted`` is None)."""
    offered = list(sim.capabilities().engines_available)
    if not wanted:
        return offered
    missing = [e for e in wanted if e not in offered]
    if missing:
        raise InvalidArgumentError(f"engine(s) {', '.join(missing)} not offered by daemon "
                                   f"{sim.instance!r}, which has {', '.join(offered)}")
    return list(wanted)


def law_context(sim: Client, engine: str, seed: int, index: int) -> LawContext:
    """What an experiment needs of the daemon's current world, and its seeded generator
    (seeded by the run's seed and the experiment's place, so --only changes no value)."""
    params = sim.get_params()
    gravity = -float(params["gravity"][2]) if "gravity" in params else STANDARD_GRAVITY
    return LawContext(engine, sim.capabilities(), sim.status().timestep, gravity,
                      np.random.default_rng([seed, index]))


def run_engine(sim: Client, engine: str, experiments: Sequence[Experiment], seed: int,
               progress: Progress | None = None,
               params: dict[str, Any] | None = None) -> EngineLaws:
    """Each experiment on its own fresh world of ``engine`` (with ``params``, else the
    engine's defaults); an experiment the daemon refuses gives one check with no value
    and the error as its note."""
    began = time.perf_counter()
    sim.load_world(engine, params)
    ctx = law_context(sim, engine, seed, 0)
    record = EngineLaws(engine, ctx.capabilities.engine_version, ctx.timestep, ctx.gravity)
    for experiment in experiments:
        if progress is not None:
            progress(engine, experiment.key)
        sim.load_world(engine, params)
        ctx = law_context(sim, engine, seed, KEYS.index(experiment.key))
        try:
            outcome = experiment.run(sim, ctx)
        except GaltonError as error:
            record.checks.append(Check(experiment.key, "(the run failed)", "", 0.0, None, 0.0,
                                       "", note=f"{type(error).__name__}: {error}"))
            continue
        checks, series = outcome if isinstance(outcome, tuple) else (outcome, {})
        record.checks.extend(checks)
        record.series.update({name: {"t": [float(f"{t:.6g}") for t in data[0]],
                                     "y": [float(f"{y:.6g}") for y in data[1]]}
                              for name, data in series.items()})
    sim.load_world(engine)
    record.wall_s = time.perf_counter() - began
    return record


def run_law(sim: Client, key: str, seed: int = 0) -> list[Check]:
    """One experiment's checks on the daemon's current world, which must be empty: what
    the conformance suite calls to hold every engine to the same law."""
    engine = sim.status().engine
    experiment = choose([key])[0]
    outcome = experiment.run(sim, law_context(sim, engine, seed, KEYS.index(key)))
    return outcome[0] if isinstance(outcome, tuple) else outcome


def run_laws(sim: Client, engines: Sequence[str] | None = None,
             only: Sequence[str] | None = None, seed: int = 0,
             progress: Progress | None = None,
             params: dict[str, Any] | None = None) -> LawResults:
    """The suite over ``engines`` (default: every engine the daemon offers), each world
    loaded with ``params`` (default: the engine's own defaults)."""
    experiments = choose(only)
    chosen = engines_of(sim, engines)
    records = [run_engine(sim, engine, experiments, seed, progress, params)
               for engine in chosen]
    return LawResults(records, {"engines": chosen, "laws": [e.key for e in experiments],
                                "seed": seed, "instance": sim.instance,
                                "params": params or {}})
