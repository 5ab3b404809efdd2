"""A whole benchmark run: engines × ball counts × repetitions, trial after trial."""

from __future__ import annotations

import dataclasses
import datetime as dt
import importlib.metadata
import os
import platform
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.analysis.board import BoardSpec, ReleaseSpec
from galton.analysis.board_release import nominal_positions
from galton.analysis.errors import AnalysisError
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.client.bench.defaults import (
    DEFAULT_BALLS,
    DEFAULT_ENGINES,
    DEFAULT_MAX_SIM_TIME_S,
    DEFAULT_REPETITIONS,
)
from galton.client.bench.executor import Executor, LocalExecutor, TrialHooks
from galton.client.bench.picture import Animation
from galton.client.bench.picture import take_pictures as take_pictures  # moved; kept here
from galton.client.bench.trial import DEFAULT_CHECK_INTERVAL_S, TrialConfig
from galton.client.sdk.client import Client
from galton.client.sdk.recording import SUFFIX as RECORDING_SUFFIX
from galton.protocol import ENGINE_NAMES, InvalidArgumentError
from galton.protocol.errors import did_you_mean


@dataclass
class ExperimentConfig:
    """Everything ``galton-client bench`` runs, as a value."""

    board: BoardSpec
    engines: tuple[str, ...] = DEFAULT_ENGINES
    balls: tuple[int, ...] = DEFAULT_BALLS
    repetitions: int = DEFAULT_REPETITIONS
    release: str | None = None
    seed: int = 0
    max_sim_time: float = DEFAULT_MAX_SIM_TIME_S
    check_interval: float = DEFAULT_CHECK_INTERVAL_S
    extra: dict[str, Any] = field(default_factory=dict)
    # RTF-only trials: each stops after this much physics wall time (None: until rest).
    max_wall_time: float | None = None
    # A folder to save each trial's recording in, for `galton-client view` (None: none).
    recordings: Path | None = None

    def __post_init__(self) -> None:
        if self.repetitions < 1:
            raise InvalidArgumentError(f"repetitions must be at least 1, got {self.repetitions}")
        if not self.balls or min(self.balls) < 1:
            raise InvalidArgumentError(f"ball counts must be positive, got {self.balls}")
        if self.max_wall_time is not None and not self.max_wall_time > 0:
            raise InvalidArgumentError(
                f"max_wall_time must be above 0 s (or None), got {self.max_wall_time}")
        if not self.engines:
            raise InvalidArgumentError("name at least one engine")
        check_engines(self.engines)
        for balls in sorted(set(self.balls)):
            try:
                nominal_positions(self.board_for(balls))
            except AnalysisError as error:
                raise InvalidArgumentError(f"--balls {balls} on board "
                                           f"{self.board.name!r}: {error}") from error

    def board_for(self, balls: int) -> BoardSpec:
        """The board with this ball count and the release mode asked for."""
        ball = dataclasses.replace(self.board.ball, count=balls)
        release = self.board.release
        if self.release is not None:
            release = ReleaseSpec(self.release, release.interval, release.stream_height,
                                  release.gap)
        return self.board.replace(ball=ball, release=release)

    def trials(self) -> list[TrialConfig]:
        """The plan: for each engine, each ball count, each repetition."""
        return [TrialConfig(engine, self.board_for(balls), rep, self.seed, self.max_sim_time,
                            self.check_interval,
                            recording=self.recording_of(engine, balls, rep),
                            max_wall_time=self.max_wall_time)
                for engine in self.engines for balls in self.balls
                for rep in range(self.repetitions)]

    def recording_of(self, engine: str, balls: int, repetition: int) -> Path | None:
        """Where a trial's recording goes (one file per trial, named by what it ran)."""
        if self.recordings is None:
            return None
        return self.recordings / f"{engine}_{balls}balls_rep{repetition + 1}{RECORDING_SUFFIX}"


def check_engines(engines: tuple[str, ...]) -> None:
    """Refuse an unknown or repeated engine before any trial runs (a typo found after ten
    trials would waste them)."""
    for engine in engines:
        if engine not in ENGINE_NAMES:
            raise InvalidArgumentError(
                f"--engines: unknown engine {engine!r}{did_you_mean(engine, ENGINE_NAMES)}; "
                f"known: {', '.join(ENGINE_NAMES)}")
    repeated = sorted({e for e in engines if engines.count(e) > 1})
    if repeated:
        raise InvalidArgumentError(f"--engines names {', '.join(repeated)} more than once")


def run_experiment(clients: dict[str, Client], config: ExperimentConfig,
                   on_trial: Callable[[TrialConfig, TrialRecord], None] | None = None,
                   pictures: Path | None = None, animation: Animation | None = None,
                   ) -> ExperimentResults:
    """Run every trial of the plan on the daemon serving its engine. With ``pictures`` (a
    folder), each engine's first trial is rendered there once recorded (board_ENGINE.png)
    and, with ``animation``, replayed as an animated PNG (board_ENGINE_trial.png)."""
    hooks = TrialHooks(on_trial=None if on_trial is None else (
        lambda _worker, trial, record: on_trial(trial, record)))
    return run_plan(LocalExecutor(clients), config, hooks, pictures, animation)


def run_plan(executor: Executor, config: ExperimentConfig, hooks: TrialHooks | None = None,
             pictures: Path | None = None, animation: Animation | None = None,
             plan: list[TrialConfig] | None = None) -> ExperimentResults:
    """Run the plan (``config``'s, unless one is given: a sweep's grid) through
    ``executor`` (executor.py); the results record the executor and what it adds."""
    ran = executor.run(config.trials() if plan is None else plan, hooks or TrialHooks(),
                       pictures, animation)
    extra = ran.extra | ({"pictures": ran.pictures} if ran.pictures else {})
    results = experiment_results(ran.records, config, extra, ran.hosts)
    results.executor = executor.describe()
    return results


def experiment_results(records: list[TrialRecord], config: ExperimentConfig,
                       extra: dict[str, Any] | None = None,
                       hosts: dict[str, dict[str, Any]] | None = None) -> ExperimentResults:
    """The records with what is needed to trust and re-run them: date, this host, versions,
    the command line, the config's extra (and ``extra``), the daemons' hosts."""
    return ExperimentResults(trials=records, date=dt.datetime.now(dt.UTC).isoformat(),
                             host=host_description(), versions=versions(),
                             command=" ".join(sys.argv),
                             extra=dict(config.extra) | (extra or {}), hosts=hosts or {})


def host_description() -> str:
    return f"{platform.node()} ({platform.machine()}, {os.cpu_count()} CPUs, {platform.system()})"


def versions() -> dict[str, str]:
    found = {"python": platform.python_version()}
    for package in ("galton-bridge", "eclipse-zenoh", "mujoco", "pybullet", "dartpy", "numpy",
                    "scipy"):
        try:
            found[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            found[package] = "not installed"
    return found
