"""The plan on Ray: ``galton-client bench --ray ADDRESS`` (and ``sweep``, ``report-card``).

Each worker is a Ray actor (``ray_actor.DaemonActor``) that starts a daemon of its own on
its node's loopback and holds the CPUs it reserves; each trial is a task on an actor, one in
flight per actor, and the records stream back as they finish (``ray.wait``). Faults are
Ray's to handle: an actor whose daemon dies exits, Ray restarts it (``max_restarts``: a
fresh daemon, on any node with room) and reruns the trial it held (``max_task_retries``).
The driver learns of it from the actor's incarnation, and the results say which trials were
retried. Once no trial waits, an actor that finishes is stopped if the cluster is full, so
that an actor displaced by a lost node finds room to restart in. A trial is seeded by its
own config, so it gives the same bins here as on a plain run.

This module and ``ray_actor`` are the only ones that import ``ray`` (the ``[cluster]``
extra); nothing imports them unless ``--ray`` is given.
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import ray
from ray.exceptions import (
    ActorUnavailableError,
    GetTimeoutError,
    RayActorError,
    RayTaskError,
)

from galton.analysis.records import TrialRecord
from galton.client.bench.executor import Ran, Retry, TrialHooks
from galton.client.bench.picture import Animation, first_trials
from galton.client.bench.ray_actor import (
    PICTURES_FOLDER,
    RECORDING_KEY,
    ActorFacts,
    ActorResult,
    DaemonActor,
)
from galton.client.bench.trial import TrialConfig
from galton.protocol import DaemonUnreachableError, GaltonError, InvalidArgumentError

RAY_LOCAL = "local"
# How often Ray may restart one actor, and rerun one trial, before the run fails.
MAX_RESTARTS = 3
MAX_TASK_RETRIES = 3
ACTOR_START_TIMEOUT_S = 300.0
CLOSE_TIMEOUT_S = 30.0
RETRY_REASON = "its actor died (its daemon or node lost); Ray restarted it and reran the trial"


@dataclass(frozen=True)
class RaySettings:
    """Where and how wide: a cluster address (``local``, ``auto``, ``ray://HOST:PORT``),
    the CPUs each actor reserves, and how many actors (None: as many as the cluster's CPUs
    hold, at most the trials)."""

    address: str = RAY_LOCAL
    cpus_per_daemon: float = 1.0
    actors: int | None = None

    def __post_init__(self) -> None:
        if not self.cpus_per_daemon > 0:
            raise InvalidArgumentError(
                f"--ray-cpus-per-daemon must be above 0, got {self.cpus_per_daemon}")
        if self.actors is not None and self.actors < 1:
            raise InvalidArgumentError(f"--ray-actors must be at least 1, got {self.actors}")


class RayExecutor:
    """The executor over ``DaemonActor``s (executor.py); start it with ``ray_executor``."""

    def __init__(self, settings: RaySettings, engine: str, timeout: float) -> None:
        self.settings = settings
        self.engine = engine
        self.timeout = timeout
        self.actors: dict[str, Any] = {}  # name -> actor handle (None once stopped)
        self.facts: dict[str, ActorFacts] = {}
        self.incarnations: dict[str, str] = {}
        self.retried: list[Retry] = []  # every run's, in the order seen
        self._remote = ray.remote(DaemonActor).options(
            num_cpus=settings.cpus_per_daemon, max_restarts=MAX_RESTARTS,
            max_task_retries=MAX_TASK_RETRIES, scheduling_strategy="SPREAD")

    def workers(self) -> list[str]:
        return list(self.actors)

    def describe(self) -> dict[str, Any]:
        return {"kind": "ray", "address": self.settings.address,
                "nodes": len({f.node for f in self.facts.values()}),
                "actors": len(self.actors), "cpus_per_actor": self.settings.cpus_per_daemon,
                "retried": [r.to_dict() for r in self.retried]}

    def run(self, plan: list[TrialConfig], hooks: TrialHooks, pictures: Path | None = None,
            animation: Animation | None = None) -> Ran:
        self.start([name for name, actor in self.actors.items() if actor is None])
        return _RayRun(self, plan, hooks, pictures, animation).run()

    def start(self, names: list[str]) -> None:
        """These actors started (spread over the nodes), each with its daemon ready."""
        started: dict[str, Any] = {
            name: self._remote.remote(name, self.engine, self.timeout) for name in names}
        self.actors |= started
        try:
            facts = ray.get([a.facts.remote() for a in started.values()],
                            timeout=ACTOR_START_TIMEOUT_S)
        except (RayActorError, RayTaskError, GetTimeoutError) as error:
            raise DaemonUnreachableError(
                f"--ray {self.settings.address}: the actors' daemons did not start ({error}); "
                "each node needs galton-bridge with its engines and the [cluster] extra, in "
                "the same Python as the driver") from error
        for fact in facts:
            self.facts[fact.name] = fact
            self.incarnations[fact.name] = fact.incarnation

    def stop(self, name: str) -> None:
        """Stop this actor's daemon, then the actor (its CPUs freed)."""
        actor, self.actors[name] = self.actors[name], None
        if actor is not None:
            try:
                ray.wait([actor.close.remote()], timeout=CLOSE_TIMEOUT_S)
            finally:
                ray.kill(actor)

    def make_room(self, name: str) -> None:
        """Stop this idle actor if the cluster has no room for one more: an actor that
        lost its node may be waiting for that room to restart in."""
        free = ray.available_resources().get("CPU", 0.0)  # type: ignore[no-untyped-call]
        if free < self.settings.cpus_per_daemon:
            self.stop(name)

    def close(self) -> None:
        for name in list(self.actors):
            self.stop(name)


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
        self.unavailable: dict[int, int] = {}  # trial -> times its actor was lost under it

    def run(self) -> Ran:
        for name in self.executor.actors:
            self.submit(name)
        while self.in_flight:
            (ready,), _ = ray.wait(list(self.in_flight), num_returns=1)
            name, index, incarnation = self.in_flight.pop(ready)
            result = self.result(ready, name, index)
            if result is None:  # lost with its node: again, once Ray has restarted it
                self.send(name, index, incarnation)
                continue
            self.settle(name, index, incarnation, result)
            if not self.submit(name) and self.in_flight:
                self.executor.make_room(name)
        records = [r for r in self.records if r is not None]
        hosts = {name: f.host for name, f in self.executor.facts.items()}
        return Ran(records, {}, self.taken, hosts)

    def submit(self, name: str) -> bool:
        """Hand this actor the next trial; False if none is left."""
        if not self.pending:
            return False
        index = self.pending.popleft()
        self.send(name, index, self.executor.incarnations[name])
        self.hooks.started(name, self.plan[index])
        return True

    def send(self, name: str, index: int, incarnation: str) -> None:
        """The trial as a task on the actor (queued by Ray while the actor restarts)."""
        ref = self.executor.actors[name].run.remote(self.plan[index], index in self.firsts,
                                                    self.animation)
        self.in_flight[ref] = (name, index, incarnation)

    def result(self, ref: Any, name: str, index: int) -> ActorResult | None:
        """The trial's result; None if its actor was lost under it (a node lost: Ray
        gives such a task up at once, though it restarts the actor); the trial's own error
        if it failed, or why Ray gave it up."""
        result: ActorResult | None = fetched(ref, index, self.unavailable,
                                             lambda error: self.not_run(name, index, error))
        return result

    def not_run(self, name: str, index: int, error: RayActorError) -> DaemonUnreachableError:
        trial = self.plan[index]
        return DaemonUnreachableError(
            f"Ray actor {name} died and was not restarted (up to {MAX_RESTARTS} restarts, "
            f"{MAX_TASK_RETRIES} reruns of a trial): trial {index + 1} ({trial.engine}, "
            f"{trial.balls} balls, rep {trial.repetition + 1}) did not run: {error}")

    def settle(self, name: str, index: int, incarnation: str, result: ActorResult) -> None:
        trial = self.plan[index]
        if result.incarnation != incarnation:
            retry = Retry(name, index, trial.engine, trial.balls, trial.repetition,
                          RETRY_REASON)
            self.executor.retried.append(retry)
            if self.hooks.on_retry is not None:
                self.hooks.on_retry(retry)
        self.executor.incarnations[name] = result.incarnation
        self.write_files(trial, result)
        self.records[index] = result.record
        self.hooks.finished(name, trial, result.record)

    def write_files(self, trial: TrialConfig, result: ActorResult) -> None:
        """The actor's pictures into the pictures folder, its recording where asked."""
        pictures = f"{PICTURES_FOLDER}/"
        for name, data in result.files.items():
            if name == RECORDING_KEY and trial.recording is not None:
                target = trial.recording
            elif self.pictures is not None and name.startswith(pictures):
                target = self.pictures / name.removeprefix(pictures)
            else:
                continue
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        self.taken |= result.taken



def fetched(ref: Any, index: int, unavailable: dict[int, int],
            lost: Callable[[RayActorError], DaemonUnreachableError]) -> Any:
    """A task's result; None if its actor was lost under it and task ``index`` may go again
    (Ray gives such a task up at once, though it restarts the actor; counted in
    ``unavailable``); the task's own GaltonError if it failed; ``lost(error)`` when Ray
    gave it up for good."""
    try:
        return ray.get(ref)
    except RayTaskError as error:
        if isinstance(error.cause, GaltonError):
            raise error.cause from None
        raise
    except ActorUnavailableError as error:
        unavailable[index] = unavailable.get(index, 0) + 1
        if unavailable[index] <= MAX_TASK_RETRIES:
            return None
        raise lost(error) from error
    except RayActorError as error:
        raise lost(error) from error

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


@contextmanager
def ray_executor(settings: RaySettings, engine: str, timeout: float, most: int
                 ) -> Iterator[RayExecutor]:
    """A RayExecutor on the cluster at ``settings.address`` with its actors started (their
    daemons with ``engine``; at most ``most`` unless the settings say); on exit the actors
    are stopped and a Ray instance started here (``local``) is shut down."""
    owned = connect(settings.address)
    try:
        executor = RayExecutor(settings, engine, timeout)
        try:
            executor.start([f"ray-{i + 1}" for i in range(actor_count(settings, most))])
            yield executor
        finally:
            executor.close()
    finally:
        if owned:
            ray.shutdown()
