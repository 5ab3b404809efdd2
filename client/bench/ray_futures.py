"""An ensemble's futures over Ray actors: ``galton-client predict --futures N --ray ADDRESS``.

The snapshot's blob is put in Ray's object store once; each batch (``futures.batches``) is
a task on a ``DaemonActor``, which restores the snapshot into its daemon the first time it
sees its digest and predicts the batch's futures from it. One batch in flight per actor,
results taken as they finish (``ray.wait``). An actor whose daemon dies is restarted by Ray
and its batch rerun (as ``bench --ray``'s trials, ``ray_executor.py``); a rerun batch is the
same futures bit for bit (its noise is addressed by ``first_future`` in the seed's stream).

Imported only when ``--ray`` is given (or by a program that asks for it).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import Any

import ray
from ray.exceptions import RayActorError

from galton.client.bench.futures import Start
from galton.client.bench.ray_actor import FutureBatch
from galton.client.bench.ray_executor import (
    RayExecutor,
    RaySettings,
    fetched,
    ray_executor,
)
from galton.client.sdk.values import Prediction
from galton.protocol import DaemonUnreachableError


@dataclass(frozen=True)
class BatchRetry:
    """A batch that ran again because its actor died under it (Ray restarted the actor)."""

    worker: str
    batch: int
    first_future: int
    futures: int

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


class RayFutures:
    """A ``FutureRunner`` (futures.py) over a RayExecutor's actors."""

    def __init__(self, executor: RayExecutor) -> None:
        self.executor = executor
        self.retried: list[BatchRetry] = []

    def width(self) -> int:
        return len(self.executor.actors)

    def map(self, start: Start, variants: Sequence[Mapping[str, Any]]) -> list[Prediction]:
        self.executor.start([name for name, a in self.executor.actors.items() if a is None])
        blob = ray.put(start.blob)
        return _Spread(self, start, [blob], list(variants)).run()


class _Spread:
    """One ensemble's batches over the actors: each idle actor the next batch."""

    def __init__(self, runner: RayFutures, start: Start, blob: list[Any],
                 variants: list[Mapping[str, Any]]) -> None:
        self.runner, self.start, self.blob, self.variants = runner, start, blob, variants
        self.executor = runner.executor
        self.pending = deque(range(len(variants)))
        self.in_flight: dict[Any, tuple[str, int, str]] = {}
        self.found: list[Prediction | None] = [None] * len(variants)
        self.unavailable: dict[int, int] = {}

    def run(self) -> list[Prediction]:
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
            self.submit(name)
        return [p for p in self.found if p is not None]

    def submit(self, name: str) -> None:
        if self.pending:
            self.send(name, self.pending.popleft(), self.executor.incarnations[name])

    def send(self, name: str, index: int, incarnation: str) -> None:
        ref = self.executor.actors[name].predict.remote(
            self.start.digest, self.blob, self.start.engine, dict(self.variants[index]))
        self.in_flight[ref] = (name, index, incarnation)

    def result(self, ref: Any, name: str, index: int) -> FutureBatch | None:
        """The batch; None if its actor was lost under it (Ray gives such a task up at
        once, though it restarts the actor); the batch's own error if it failed."""
        result: FutureBatch | None = fetched(ref, index, self.unavailable,
                                             lambda error: self.not_run(name, index, error))
        return result

    def not_run(self, name: str, index: int, error: RayActorError) -> DaemonUnreachableError:
        variant = self.variants[index]
        return DaemonUnreachableError(
            f"Ray actor {name} died and was not restarted: futures "
            f"{variant['first_future']}..{variant['first_future'] + variant['futures'] - 1} "
            f"did not run: {error}")

    def settle(self, name: str, index: int, incarnation: str, result: FutureBatch) -> None:
        if result.incarnation != incarnation:
            variant = self.variants[index]
            self.runner.retried.append(BatchRetry(name, index, variant["first_future"],
                                                  variant["futures"]))
        self.executor.incarnations[name] = result.incarnation
        self.found[index] = result.prediction


@contextmanager
def ray_futures(settings: RaySettings, engine: str, timeout: float, most: int
                ) -> Iterator[RayFutures]:
    """A RayFutures on the cluster at ``settings.address`` (its actors' daemons started
    with ``engine``; at most ``most`` actors unless the settings say), stopped on exit."""
    with ray_executor(settings, engine, timeout, most) as executor:
        yield RayFutures(executor)
