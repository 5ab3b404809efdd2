"""The plan on Ray: ``galton-client bench --ray ADDRESS`` (and ``sweep``, ``report-card``).

Each worker is a Ray actor (``DaemonActor``) that starts a daemon of its own on its node's
loopback and holds the CPUs it reserves; each trial is a task on an actor, and the records
stream back as they finish (``ray.wait``). Faults are Ray's to handle: an actor exits as
soon as its daemon dies (a real process death, which Ray sees), Ray restarts it
(``max_restarts``: a fresh daemon) and reruns the trial it held (``max_task_retries``).
The driver learns of it from the actor's incarnation (a new one per start), and the
results say which trials were retried. A trial is seeded by its own config, so it gives the
same bins here as on a plain run.

This is the only module that imports ``ray`` (the ``[cluster]`` extra); nothing imports it
unless ``--ray`` is given.
"""

from __future__ import annotations

import logging
import os
import tempfile
import threading
import uuid
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import ray
from ray.exceptions import RayActorError, RayTaskError

from galton.analysis.records import TrialRecord
from galton.client.bench.executor import Ran, Retry, TrialHooks
from galton.client.bench.picture import Animation, first_trials, take_pictures
from galton.client.bench.trial import TrialConfig, run_trial
from galton.client.sdk.client import Client
from galton.client.sdk.embedded import EmbeddedDaemon
from galton.protocol import (
    DaemonUnreachableError,
    GaltonError,
    InvalidArgumentError,
    RequestTimeoutError,
)

RAY_LOCAL = "local"
# How often Ray may restart one actor, and rerun one trial, before the run fails.
MAX_RESTARTS = 3
MAX_TASK_RETRIES = 3
# The exit status of an actor whose daemon died (any non-zero status: Ray restarts it).
DAEMON_LOST_EXIT = 75
ACTOR_START_TIMEOUT_S = 300.0
CLOSE_TIMEOUT_S = 30.0
RECORDING_KEY = "recording"


@dataclass(frozen=True)
class RaySettings:
    """Where and how wide: a cluster address (``local``, ``auto``, ``ray://HOST:PORT``),
    the CPUs each actor reserves, and how many actors (None: as many as the cluster's CPUs
    hold, at most ``most``)."""

    address: str = RAY_LOCAL
    cpus_per_daemon: float = 1.0
    actors: int | None = None

    def __post_init__(self) -> None:
        if not self.cpus_per_daemon > 0:
            raise InvalidArgumentError(
                f"--ray-cpus-per-daemon must be above 0, got {self.cpus_per_daemon}")
        if self.actors is not None and self.actors < 1:
            raise InvalidArgumentError(f"--ray-actors must be at least 1, got {self.actors}")


@dataclass(frozen=True)
class ActorFacts:
    """What an actor says of itself: its daemon (pid, endpoint, instance), its node, and
    its incarnation (new at each start, so a restart is seen)."""

    name: str
    incarnation: str
    node: str
    daemon_pid: int
    endpoint: str
    host: dict[str, Any]


@dataclass
class ActorResult:
    """A finished trial: its record, the incarnation that ran it, and the files it made
    (pictures, a recording) as bytes, since the actor's node may not be the driver's."""

    record: TrialRecord
    incarnation: str
    files: dict[str, bytes] = field(default_factory=dict)
    taken: dict[str, str] = field(default_factory=dict)


class DaemonActor:
    """A Ray actor hosting one daemon on its node's loopback; trials run through the SDK.

    It exits the moment its daemon dies (or stops answering mid-trial), so Ray sees a dead
    actor, restarts it with a fresh daemon and reruns the trial it held."""

    def __init__(self, name: str, engine: str, timeout: float) -> None:
        self.name = name
        self.incarnation = uuid.uuid4().hex
        self.closing = False
        self.daemon = EmbeddedDaemon(engine, instance=name).start()
        self.client = Client(name, self.daemon.endpoint, timeout=timeout)
        threading.Thread(target=self._exit_with_daemon, name="daemon-watch",
                         daemon=True).start()

    def _exit_with_daemon(self) -> None:
        assert self.daemon.process is not None
        self.daemon.process.wait()
        if not self.closing:
            os._exit(DAEMON_LOST_EXIT)

    def facts(self) -> ActorFacts:
        assert self.daemon.process is not None
        return ActorFacts(self.name, self.incarnation, ray.get_runtime_context().get_node_id(),
                          self.daemon.process.pid, self.daemon.endpoint,
                          self.client.capabilities().host)

    def run(self, trial: TrialConfig, pictures: bool, animation: Animation | None
            ) -> ActorResult:
        """One trial (with its pictures, if asked, and its recording, as bytes)."""
        with tempfile.TemporaryDirectory(prefix="galton-ray-") as folder:
            here = Path(folder)
            local = trial if trial.recording is None else replace(
                trial, recording=here / RECORDING_KEY)
            try:
                record = run_trial(self.client, local)
                taken = take_pictures(self.client, trial, here / "pictures",
                                      animation) if pictures else {}
            except (DaemonUnreachableError, RequestTimeoutError):
                self.daemon.process.kill()  # type: ignore[union-attr]
                os._exit(DAEMON_LOST_EXIT)  # gone or silent: Ray restarts us, reruns it
            record.daemon = self.name
            files = {p.relative_to(here).as_posix(): p.read_bytes()
                     for p in here.rglob("*") if p.is_file()}
        return ActorResult(record, self.incarnation, files, taken)

    def close(self) -> None:
        self.closing = True
        self.client.close()
        self.daemon.stop()


class RayExecutor:
    """The executor over ``DaemonActor``s (executor.py): one trial in flight per actor."""

    def __init__(self, settings: RaySettings, actors: dict[str, Any],
                 facts: dict[str, ActorFacts]) -> None:
        self.settings = settings
        self.actors = actors
        self.facts = facts
        self.incarnations = {name: f.incarnation for name, f in facts.items()}
        self.retried: list[Retry] = []  # every run's, in the order seen

    def workers(self) -> list[str]:
        return list(self.actors)

    def describe(self) -> dict[str, Any]:
        return {"kind": "ray", "address": self.settings.address,
                "nodes": len({f.node for f in self.facts.values()}),
                "actors": len(self.actors), "cpus_per_actor": self.settings.cpus_per_daemon,
                "retried": [r.to_dict() for r in self.retried]}

    def run(self, plan: list[TrialConfig], hooks: TrialHooks, pictures: Path | None = None,
            animation: Animation | None = None) -> Ran:
        return _RayRun(self, plan, hooks, pictures, animation).run()


class _RayRun:
    """One plan over the actors: hand each idle actor the next trial, take results as
    they finish, write what they made, note the retried ones."""

    def __init__(self, executor: RayExecutor, plan: list[TrialConfig], hooks: TrialHooks,
                 pictures: Path | None, animation: Animation | None) -> None:
        self.executor, self.plan, self.hooks = executor, plan, hooks
        self.pictures, self.animation = pictures, animation
        self.firsts = first_trials(plan) if pictures is not None else {}
        self.pending = deque(range(len(plan)))
        self.in_flight: dict[Any, tuple[str, int, str]] = {}
        self.records: list[TrialRecord | None] = [None] * len(plan)
        self.taken: dict[str, str] = {}

    def run(self) -> Ran:
        for name in self.executor.actors:
            self.submit(name)
        while self.in_flight:
            (ready,), _ = ray.wait(list(self.in_flight), num_returns=1)
            name, index, incarnation = self.in_flight.pop(ready)
            self.settle(name, index, incarnation, self.result(ready, name, index))
            self.submit(name)
        records = [r for r in self.records if r is not None]
        hosts = {name: f.host for name, f in self.executor.facts.items()}
        return Ran(records, {}, self.taken, hosts)

    def submit(self, name: str) -> None:
        if not self.pending:
            return
        index = self.pending.popleft()
        trial = self.plan[index]
        ref = self.executor.actors[name].run.remote(trial, index in self.firsts,
                                                    self.animation)
        self.in_flight[ref] = (name, index, self.executor.incarnations[name])
        self.hooks.started(name, trial)

    def result(self, ref: Any, name: str, index: int) -> ActorResult:
        """The trial's result; its own error if it failed, or why Ray gave it up."""
        try:
            result: ActorResult = ray.get(ref)
        except RayTaskError as error:
            cause = error.cause
            if isinstance(cause, GaltonError):
                raise cause from None
            raise
        except RayActorError as error:
            trial = self.plan[index]
            raise DaemonUnreachableError(
                f"Ray actor {name} died and was not restarted (up to {MAX_RESTARTS} restarts, "
                f"{MAX_TASK_RETRIES} reruns of a trial): trial {index + 1} ({trial.engine}, "
                f"{trial.balls} balls, rep {trial.repetition + 1}) did not run: "
                f"{error}") from error
        return result

    def settle(self, name: str, index: int, incarnation: str, result: ActorResult) -> None:
        trial = self.plan[index]
        if result.incarnation != incarnation:
            retry = Retry(name, index, trial.engine, trial.balls, trial.repetition,
                          "its actor died (its daemon lost) and Ray restarted it and reran "
                          "the trial")
            self.executor.retried.append(retry)
            if self.hooks.on_retry is not None:
                self.hooks.on_retry(retry)
        self.executor.incarnations[name] = result.incarnation
        self.write_files(trial, result)
        self.records[index] = result.record
        self.hooks.finished(name, trial, result.record)

    def write_files(self, trial: TrialConfig, result: ActorResult) -> None:
        """The actor's pictures into the pictures folder, its recording where asked."""
        for name, data in result.files.items():
            if name == RECORDING_KEY and trial.recording is not None:
                target = trial.recording
            elif self.pictures is not None and name.startswith("pictures/"):
                target = self.pictures / name.removeprefix("pictures/")
            else:
                continue
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        self.taken |= result.taken


def connect(address: str) -> bool:
    """Join the cluster at ``address`` (``local``: start one on this machine); False if
    this process was already connected (a driver of its own: its connection is used)."""
    if ray.is_initialized():
        return False
    quiet: dict[str, Any] = {"log_to_driver": False, "logging_level": logging.WARNING}
    try:
        if address == RAY_LOCAL:
            ray.init(address="local", include_dashboard=False, **quiet)
        else:
            ray.init(address=address, **quiet)
    except (ConnectionError, RuntimeError, ValueError) as error:
        raise DaemonUnreachableError(f"--ray {address}: cannot join a Ray cluster there "
                                     f"({error})") from error
    return True


def actor_count(settings: RaySettings, most: int) -> int:
    """How many actors: those asked, or as many as the cluster's CPUs hold (at most
    ``most``); refused when the cluster cannot hold them."""
    cpus = float(ray.cluster_resources().get("CPU", 0.0))  # type: ignore[no-untyped-call]
    fit = int(cpus // settings.cpus_per_daemon + 1e-9)
    wanted = settings.actors or max(1, min(fit, most))
    if wanted > fit:
        raise InvalidArgumentError(
            f"{wanted} Ray actor(s) of {settings.cpus_per_daemon:g} CPU(s) each need "
            f"{wanted * settings.cpus_per_daemon:g} CPUs; the cluster at "
            f"{settings.address} has {cpus:g}")
    return wanted


def start_actors(count: int, settings: RaySettings, engine: str, timeout: float
                 ) -> tuple[dict[str, Any], dict[str, ActorFacts]]:
    """``count`` actors spread over the nodes, each with its daemon ready."""
    remote = ray.remote(DaemonActor).options(
        num_cpus=settings.cpus_per_daemon, max_restarts=MAX_RESTARTS,
        max_task_retries=MAX_TASK_RETRIES, scheduling_strategy="SPREAD")
    actors: dict[str, Any] = {f"ray-{i + 1}": remote.remote(f"ray-{i + 1}", engine, timeout)
                              for i in range(count)}
    try:
        facts = ray.get([a.facts.remote() for a in actors.values()],
                        timeout=ACTOR_START_TIMEOUT_S)
    except (RayActorError, RayTaskError, ray.exceptions.GetTimeoutError) as error:
        stop_actors(actors)
        raise DaemonUnreachableError(
            f"--ray {settings.address}: the actors' daemons did not start ({error}); each "
            "node needs galton-bridge with the engines installed") from error
    return actors, dict(zip(actors, facts, strict=True))


def stop_actors(actors: dict[str, Any]) -> None:
    """Stop each actor's daemon, then the actor."""
    closing = [a.close.remote() for a in actors.values()]
    try:
        ray.wait(closing, num_returns=len(closing), timeout=CLOSE_TIMEOUT_S)
    finally:
        for actor in actors.values():
            ray.kill(actor)


@contextmanager
def ray_executor(settings: RaySettings, engine: str, timeout: float, most: int
                 ) -> Iterator[RayExecutor]:
    """A RayExecutor on the cluster at ``settings.address`` with its actors started (their
    daemons with ``engine``); on exit the actors are stopped and a Ray instance started
    here (``local``) is shut down."""
    owned = connect(settings.address)
    try:
        actors, facts = start_actors(actor_count(settings, most), settings, engine, timeout)
        try:
            yield RayExecutor(settings, actors, facts)
        finally:
            stop_actors(actors)
    finally:
        if owned:
            ray.shutdown()
