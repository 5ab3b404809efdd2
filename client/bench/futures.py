"""Ensembles of futures larger than one ``predict`` call, or than one machine.

A world's snapshot (its blob, taken once) is the start every future forks from; the
ensemble is cut into batches, each a ``predict`` of ``futures`` M from ``first_future`` K
with the ensemble's one seed, so that future K+i of a batch is future K+i of the whole,
bit for bit, wherever it ran (docs/protocol.md, ``predict``). A ``FutureRunner`` runs the
batches somewhere: ``LocalFutures`` on one daemon, ``RayFutures`` (``ray_futures.py``)
over Ray actors each holding a daemon with the snapshot restored. ``merge`` lays the
batches' futures end to end and recomputes ``spread`` over all of them, as the daemon does
for one call.

This module does not import ``ray``.
"""

from __future__ import annotations

import hashlib
import math
import secrets
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Protocol

import numpy as np

from galton.client.sdk.client import Client
from galton.client.sdk.values import Prediction
from galton.protocol import GaltonError, InvalidArgumentError
from galton.protocol.requests import MAX_FIRST_FUTURE, MAX_FUTURES

# Snapshots a daemon keeps restored (each in a side world of its own), the oldest dropped.
KEPT_SNAPSHOTS = 2
WORLD_PREFIX = "ensemble-"


@dataclass(frozen=True)
class Start:
    """What every future forks from: a snapshot's blob, its engine, its digest (by which a
    daemon that already restored it knows it), and the present of the world it was taken
    from (the ensemble is stamped with it, as a prediction is with its world's present)."""

    blob: bytes
    engine: str
    digest: str = field(default="")
    step: int | None = None
    sim_time: float | None = None

    def __post_init__(self) -> None:
        if not self.digest:
            object.__setattr__(self, "digest", digest_of(self.blob))


def digest_of(blob: bytes) -> str:
    return hashlib.blake2b(blob, digest_size=16).hexdigest()


def start_of(sim: Client, slot: str | None = None) -> Start:
    """The start of an ensemble: ``sim``'s world now, or its snapshot ``slot`` (restored
    into a side world of its own for the time of taking its blob)."""
    present = sim.status()
    if slot is None:
        taken = sim.snapshot(blob=True)
        present = replace(present, step=taken.step, sim_time=taken.sim_time)
    else:
        name = f"{WORLD_PREFIX}slot-{secrets.token_hex(4)}"
        engines = {kept.slot: kept.engine for kept in sim.snapshots()}
        sim.create_world(name, engine=engines.get(slot))  # an unknown slot: restore says
        try:
            side = sim.world(name)
            side.restore(slot=slot)
            taken = side.snapshot(blob=True)
        finally:
            sim.delete_world(name)
    assert taken.blob is not None
    return Start(taken.blob, taken.engine, step=present.step, sim_time=present.sim_time)


class SnapshotWorlds:
    """The snapshots a daemon holds restored, by digest, each in a side world (at most
    ``keep``, the least recently used deleted first): each snapshot is restored once."""

    def __init__(self, sim: Client, keep: int = KEPT_SNAPSHOTS) -> None:
        self.sim = sim
        self.keep = keep
        self.held: OrderedDict[str, str] = OrderedDict()  # digest -> world

    def world(self, digest: str, engine: str, blob: Callable[[], bytes]) -> Client:
        """The world holding this snapshot (``blob`` fetched only when not held yet)."""
        name = self.held.get(digest)
        if name is None:
            while len(self.held) >= self.keep:
                self.sim.delete_world(self.held.popitem(last=False)[1])
            name = f"{WORLD_PREFIX}{digest}"
            self.sim.create_world(name, engine=engine)
            try:
                self.sim.world(name).restore(blob=blob())
            except GaltonError:
                self.sim.delete_world(name)  # a blob refused: nothing held, nothing left
                raise
            self.held[digest] = name
        self.held.move_to_end(digest)
        return self.sim.world(name)

    def close(self) -> None:
        while self.held:
            self.sim.delete_world(self.held.popitem()[1])


class FutureRunner(Protocol):
    """Runs batches of one ensemble: each ``variant`` is ``Client.predict``'s keyword
    arguments, all from the same start; the predictions come back in their order."""

    def width(self) -> int:
        """How many batches it runs at once (the ensemble is cut to keep them busy)."""
        ...

    def map(self, start: Start, variants: Sequence[Mapping[str, Any]]) -> list[Prediction]:
        ...


class LocalFutures:
    """The batches one after another on one daemon (the snapshot restored there once)."""

    def __init__(self, sim: Client) -> None:
        self.worlds = SnapshotWorlds(sim)

    def width(self) -> int:
        return 1

    def map(self, start: Start, variants: Sequence[Mapping[str, Any]]) -> list[Prediction]:
        world = self.worlds.world(start.digest, start.engine, lambda: start.blob)
        return [world.predict(**variant) for variant in variants]

    def close(self) -> None:
        self.worlds.close()


def batches(futures: int, width: int, args: Mapping[str, Any]) -> list[dict[str, Any]]:
    """The ensemble's batches as ``predict`` keyword arguments: ``width`` of them or more
    (at most MAX_FUTURES futures each), each with its ``first_future`` and its plans."""
    size = min(MAX_FUTURES, math.ceil(futures / max(1, width)))
    plans = args.get("plans")
    out = []
    for first in range(0, futures, size):
        count = min(size, futures - first)
        batch = {**args, "futures": count, "first_future": first}
        if plans is not None:
            batch["plans"] = list(plans[first:first + count])
        out.append(batch)
    return out


def predict_ensemble(runner: FutureRunner, start: Start, horizon: float, futures: int,
                     perturb: Mapping[str, Any] | None = None, seed: int | None = None,
                     **predict_args: Any) -> Prediction:
    """``futures`` futures of ``start``, ``horizon`` seconds ahead, spread over the
    runner's batches: the same, bit for bit, as one daemon's ``predict(futures=...,
    perturb=..., seed=...)`` of that start. ``predict_args`` are ``Client.predict``'s
    others (``read``, ``every``, ``plans``, ``score``, ``set_states`` ...); without a
    ``seed`` a perturbed ensemble draws one (sent back in ``Prediction.seed``)."""
    if not 1 <= futures <= MAX_FIRST_FUTURE + MAX_FUTURES:
        raise InvalidArgumentError(f"an ensemble holds 1 to "
                                   f"{MAX_FIRST_FUTURE + MAX_FUTURES} futures, not {futures}")
    plans = predict_args.get("plans")
    if plans is not None and len(plans) != futures:
        raise InvalidArgumentError(f"{len(plans)} plans for {futures} futures: give one "
                                   "plan per future")
    if perturb is not None and seed is None:
        seed = secrets.randbits(63)
    args = {"horizon": horizon, "perturb": perturb, "seed": seed, **predict_args}
    found = merge(runner.map(start, batches(futures, runner.width(), args)))
    if start.step is None or start.sim_time is None:
        return found
    return replace(found, step=start.step, sim_time=start.sim_time)


def merge(parts: Sequence[Prediction]) -> Prediction:
    """Batches' predictions as one: their futures end to end, ``spread`` over all of them
    (computed as the daemon computes it for one call), the scores end to end."""
    first = parts[0]
    if len(parts) == 1:
        return first
    for part in parts[1:]:
        if not np.array_equal(part.times, first.times):
            raise InvalidArgumentError("the batches of an ensemble sampled different times: "
                                       "they did not start from the same snapshot")

    def joined(key: str) -> np.ndarray:
        return np.concatenate([getattr(p, key) if p.futures > 1 else getattr(p, key)[None]
                               for p in parts])
    poses = joined("poses")
    spread = None if not first.names else np.stack(
        [ensemble_spread(poses[:, sample, :, :3]) for sample in range(len(first.times))])
    scores = None if first.scores is None else np.concatenate(
        [p.scores for p in parts if p.scores is not None])
    return replace(first, poses=poses, twists=joined("twists"),
                   joint_positions=joined("joint_positions"),
                   joint_velocities=joined("joint_velocities"), futures=len(poses),
                   spread=spread, scores=scores)


def ensemble_spread(positions: np.ndarray) -> np.ndarray:
    """Per body, the standard deviation of position across futures (futures, bodies, 3) ->
    (bodies,), in the daemon's own order of operations (daemon/world/futures.py ``spread``),
    so a merged ensemble's spread is the one call's bit for bit."""
    relative = positions - positions[0]
    offsets = relative - relative.mean(axis=0)
    result: np.ndarray = np.sqrt((offsets ** 2).sum(axis=2).mean(axis=0))
    return result
