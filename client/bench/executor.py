"""Where a plan's trials run: the one seam between the bench and its executors.

An executor takes the plan (a list of ``TrialConfig``, each seeded by its own config, so
its bins do not depend on where it ran) and returns every record in the plan's order,
calling the hooks as trials start and finish. Three of them:

- ``LocalExecutor`` (this module): one daemon per engine, trial after trial (plain ``bench``);
- ``PoolExecutor`` (``pool_executor.py``): daemons already running anywhere, a thread each;
- ``RayExecutor`` (``ray_executor.py``): Ray actors each hosting a daemon of their own.

``experiment.run_plan`` turns what an executor ran into an ``ExperimentResults`` whose
``executor`` field is the executor's ``describe()``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Protocol

from galton.analysis.records import TrialRecord
from galton.client.bench.picture import Animation, first_trials, take_pictures
from galton.client.bench.trial import TrialConfig, run_trial
from galton.client.sdk.client import Client


@dataclass
class Failover:
    """A daemon dropped from the pool, and the trial it left unfinished."""

    daemon: str
    trial: int  # index in the plan
    engine: str
    balls: int
    repetition: int
    error: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class Retry:
    """A trial that ran again because its worker died under it (Ray restarted the actor)."""

    worker: str
    trial: int  # index in the plan
    engine: str
    balls: int
    repetition: int
    reason: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass
class TrialHooks:
    """Callbacks as trials start and finish on a worker (a daemon, an actor). Keep them
    short: the pool calls them from its worker threads, possibly at once."""

    on_start: Callable[[str, TrialConfig], None] | None = None
    on_trial: Callable[[str, TrialConfig, TrialRecord], None] | None = None
    on_drop: Callable[[Failover], None] | None = None  # the pool dropped a daemon
    on_retry: Callable[[Retry], None] | None = None  # Ray reran a trial

    def started(self, worker: str, trial: TrialConfig) -> None:
        if self.on_start is not None:
            self.on_start(worker, trial)

    def finished(self, worker: str, trial: TrialConfig, record: TrialRecord) -> None:
        if self.on_trial is not None:
            self.on_trial(worker, trial, record)


@dataclass
class Ran:
    """What an executor hands back: every record in plan order, and what it adds to the
    results (``extra`` entries, pictures taken, the machines by worker)."""

    records: list[TrialRecord]
    extra: dict[str, Any] = field(default_factory=dict)
    pictures: dict[str, str] = field(default_factory=dict)
    hosts: dict[str, dict[str, Any]] = field(default_factory=dict)


class Executor(Protocol):
    """Runs a plan somewhere; see the module's docstring."""

    def workers(self) -> list[str]:
        """The names the hooks will be called with (a progress row each)."""
        ...

    def describe(self) -> dict[str, Any]:
        """results.json's ``executor``: ``{"kind": ...}`` and what the kind adds."""
        ...

    def run(self, plan: list[TrialConfig], hooks: TrialHooks, pictures: Path | None = None,
            animation: Animation | None = None) -> Ran:
        """Every trial of ``plan`` once, in its order. With ``pictures`` (a folder), each
        engine's first trial is rendered there (and animated, with ``animation``)."""
        ...


class LocalExecutor:
    """The plan trial after trial, each on the daemon serving its engine."""

    def __init__(self, clients: dict[str, Client]) -> None:
        self.clients = clients

    def workers(self) -> list[str]:
        return list(self.clients)

    def describe(self) -> dict[str, Any]:
        return {"kind": "local"}

    def run(self, plan: list[TrialConfig], hooks: TrialHooks, pictures: Path | None = None,
            animation: Animation | None = None) -> Ran:
        records: list[TrialRecord] = []
        firsts = first_trials(plan) if pictures is not None else {}
        taken: dict[str, str] = {}
        for index, trial in enumerate(plan):
            sim = self.clients[trial.engine]
            hooks.started(trial.engine, trial)
            record = run_trial(sim, trial)
            records.append(record)
            if index in firsts and pictures is not None:
                taken |= take_pictures(sim, trial, pictures, animation)
            hooks.finished(trial.engine, trial, record)
        return Ran(records, pictures=taken)
