"""Many daemons as one pool: ``galton-client bench --pool``.

One worker thread per daemon, each with its own Client, pulls trials from one shared queue;
any daemon serves any engine, since a trial loads its own world. A daemon whose request finds
it gone or silent (DaemonUnreachableError, RequestTimeoutError), or that will not take our
trials (ControlHeldError: another client holds its control; AccessDeniedError), is dropped
and its unfinished trial goes back to the queue for the others, so no trial is lost;
results.json records the failover. A trial is seeded by its own config, so its bins do not
depend on which daemon ran it, and the records keep the plan's order whatever order they
finished in.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.analysis.records import ExperimentResults, TrialRecord
from galton.client.bench.executor import Failover, Ran, TrialHooks
from galton.client.bench.experiment import ExperimentConfig, run_plan
from galton.client.bench.picture import Animation, first_trials, take_pictures
from galton.client.bench.trial import TrialConfig, run_trial
from galton.client.sdk.client import Client
from galton.protocol import (
    AccessDeniedError,
    ControlHeldError,
    DaemonUnreachableError,
    GaltonError,
    RequestTimeoutError,
)

# A daemon failing with these is gone, silent, or will not take our trials (another client
# holds its control; it refuses us): it is dropped and its trial re-run elsewhere.
FAILOVER_ERRORS = (DaemonUnreachableError, RequestTimeoutError, ControlHeldError,
                   AccessDeniedError)


# The pool's hooks are every executor's (kept under their old name).
PoolHooks = TrialHooks


class TrialQueue:
    """Plan indices waiting to run. A taken trial is in flight until done or put back; a
    worker finding the queue empty waits while others are in flight, since one of them may
    yet come back."""

    def __init__(self, count: int) -> None:
        self._pending = deque(range(count))
        self._in_flight = 0
        self._aborted = False
        self._changed = threading.Condition()

    def take(self) -> int | None:
        """The next trial's index, or None when none is left (or the run was aborted)."""
        with self._changed:
            while not self._pending and self._in_flight and not self._aborted:
                self._changed.wait()
            if self._aborted or not self._pending:
                return None
            self._in_flight += 1
            return self._pending.popleft()

    def done(self) -> None:
        self._settle(None)

    def put_back(self, index: int) -> None:
        """Return an unfinished trial, first in line."""
        self._settle(index)

    def abort(self) -> None:
        with self._changed:
            self._aborted = True
            self._changed.notify_all()

    def left(self) -> list[int]:
        with self._changed:
            return list(self._pending)

    def _settle(self, returned: int | None) -> None:
        with self._changed:
            self._in_flight -= 1
            if returned is not None:
                self._pending.appendleft(returned)
            self._changed.notify_all()


@dataclass
class PoolRun:
    """One pooled run of a plan: what the workers share."""

    clients: dict[str, Client]
    plan: list[TrialConfig]
    hooks: TrialHooks = field(default_factory=TrialHooks)
    pictures: Path | None = None
    animation: Animation | None = None

    def __post_init__(self) -> None:
        self.queue = TrialQueue(len(self.plan))
        self.records: list[TrialRecord | None] = [None] * len(self.plan)
        self.failovers: list[Failover] = []
        self.taken: dict[str, str] = {}
        self.errors: list[BaseException] = []
        self.firsts = first_trials(self.plan) if self.pictures is not None else {}
        self.lock = threading.Lock()

    def run(self) -> list[TrialRecord]:
        """Every trial of the plan, in its order; raise if one failed or none could run."""
        workers = [threading.Thread(target=self.work, args=(name, client),
                                    name=f"pool-{name}", daemon=True)
                   for name, client in self.clients.items()]
        for worker in workers:
            worker.start()
        try:
            for worker in workers:
                worker.join()
        finally:
            self.queue.abort()
        if self.errors:
            raise self.errors[0]
        return self.finished()

    def finished(self) -> list[TrialRecord]:
        missing = [i for i, r in enumerate(self.records) if r is None]
        if missing:
            gone = "; ".join(f"{f.daemon}: {f.error}" for f in self.failovers)
            raise DaemonUnreachableError(
                f"every daemon of the pool failed ({gone}); {len(missing)} of "
                f"{len(self.plan)} trials did not run")
        return [r for r in self.records if r is not None]

    def work(self, name: str, client: Client) -> None:
        """Take trials until none is left; stop at this daemon's first failover."""
        while (index := self.queue.take()) is not None:
            try:
                self.run_one(name, client, index)
            except FAILOVER_ERRORS as error:
                self.drop(name, index, error)
                return
            except BaseException as error:  # any other failure ends the whole run
                with self.lock:
                    self.errors.append(error)
                self.queue.abort()
                return
            self.queue.done()

    def run_one(self, name: str, client: Client, index: int) -> None:
        trial = self.plan[index]
        self.hooks.started(name, trial)
        record = run_trial(client, trial)
        record.daemon = name
        if index in self.firsts and self.pictures is not None:
            pictures = take_pictures(client, trial, self.pictures, self.animation)
            with self.lock:
                self.taken |= pictures
        with self.lock:
            self.records[index] = record
        self.hooks.finished(name, trial, record)

    def drop(self, name: str, index: int, error: GaltonError) -> None:
        trial = self.plan[index]
        failover = Failover(name, index, trial.engine, trial.balls, trial.repetition,
                            f"{type(error).__name__}: {error}")
        with self.lock:
            self.failovers.append(failover)
        self.queue.put_back(index)
        if self.hooks.on_drop is not None:
            self.hooks.on_drop(failover)


class PoolExecutor:
    """The executor over daemons already running (``bench --pool``): one worker thread
    each, a lost daemon dropped and its trial re-run on the others."""

    def __init__(self, clients: dict[str, Client],
                 hosts: dict[str, dict[str, Any]] | None = None) -> None:
        if not clients:
            raise DaemonUnreachableError("the pool has no daemon to run trials on")
        self.clients = clients
        self.hosts = hosts or {}

    def workers(self) -> list[str]:
        return list(self.clients)

    def describe(self) -> dict[str, Any]:
        """The pool's daemons, and how many machines (hostnames) they run on."""
        machines = {h.get("hostname") for h in self.hosts.values()} - {None}
        return {"kind": "pool", "daemons": len(self.clients), "nodes": len(machines) or None}

    def run(self, plan: list[TrialConfig], hooks: TrialHooks, pictures: Path | None = None,
            animation: Animation | None = None) -> Ran:
        pool = PoolRun(self.clients, plan, hooks, pictures, animation)
        records = pool.run()
        return Ran(records, {"pool": pool_record(list(self.clients), pool.failovers)},
                   pool.taken, self.hosts)


def run_pool(clients: dict[str, Client], config: ExperimentConfig,
             hosts: dict[str, dict[str, Any]] | None = None, hooks: TrialHooks | None = None,
             pictures: Path | None = None, animation: Animation | None = None,
             ) -> ExperimentResults:
    """Run the plan on every daemon of ``clients`` at once (instance -> Client); ``hosts``
    (instance -> capabilities' host map) goes into the results as they are."""
    return run_plan(PoolExecutor(clients, hosts), config, hooks, pictures, animation)


def pool_record(daemons: Sequence[str], failovers: list[Failover]) -> dict[str, Any]:
    """What results.json's ``extra.pool`` says: the daemons, and each failover."""
    return {"daemons": list(daemons), "failovers": [f.to_dict() for f in failovers]}
