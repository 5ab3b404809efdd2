"""Ensembles cut into batches on one real daemon (galton.client.bench.futures): batches of
one future each, with plans and a score, merge into the one call's ensemble bit for bit; a
slot of a side world is a start; what cannot be an ensemble is refused, nothing left over.
The same over Ray actors is in test_ray.py."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.daemons import start_daemon
from support.worlds import clean, contact_scene

from galton.client import Client, EmbeddedDaemon, InvalidArgumentError
from galton.client.bench.futures import (
    LocalFutures,
    Start,
    batches,
    predict_ensemble,
    start_of,
)

TIMEOUT_S = 30.0


class OneByOne(LocalFutures):
    """The batches of a runner as wide as the ensemble: one future per call."""

    def width(self) -> int:
        return 64


@pytest.fixture
def scene(daemons: dict[str, EmbeddedDaemon]) -> Iterator[tuple[Client, list[str]]]:
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=TIMEOUT_S) as sim, clean(sim):
        sim.load_world("mujoco")
        names = contact_scene(sim)
        sim.step(4)
        yield sim, names


def test_batches_of_one_future_with_plans_and_a_score_are_the_one_call(
        scene: tuple[Client, list[str]]) -> None:
    sim, names = scene
    dt = sim.status().timestep
    plans = [[{"at": 0.0, "wrenches": {"names": names[:1], "wrenches": [k, 0, 0, 0, 0, 0]}}]
             for k in (0.0, 1.0, -1.0)]
    ask = {"read": names, "every": 5 * dt, "plans": plans,
           "perturb": {"orientation": 0.01}, "seed": 5,
           "score": {"body": names[0], "target": [0.0, 0.0, 0.0]}}
    want = sim.predict(15 * dt, **ask)  # type: ignore[arg-type]
    runner = OneByOne(sim)
    try:
        assert [(b["first_future"], b["futures"], len(b["plans"])) for b in batches(
            3, runner.width(), ask)] == [(0, 1, 1), (1, 1, 1), (2, 1, 1)]
        found = predict_ensemble(runner, start_of(sim), 15 * dt, 3, **ask)
    finally:
        runner.close()
    assert (found.futures, found.seed, found.step) == (3, 5, want.step)
    for key in ("times", "poses", "twists", "spread", "scores"):
        np.testing.assert_array_equal(getattr(found, key), getattr(want, key), err_msg=key)


def test_a_side_worlds_slot_is_a_start_and_bad_ensembles_are_refused(
        scene: tuple[Client, list[str]]) -> None:
    sim, names = scene
    sim.fork_world("side")
    side = sim.world("side")
    side.snapshot(slot="kept")
    side.step(3)
    start = start_of(side, slot="kept")
    dt = sim.status().timestep
    want = side.predict(10 * dt, slot="kept", read=names, futures=4,
                        perturb={"position": 0.001}, seed=2)
    runner = LocalFutures(sim)
    try:
        found = predict_ensemble(runner, start, 10 * dt, 4, read=names,
                                 perturb={"position": 0.001}, seed=2)
        np.testing.assert_array_equal(found.poses, want.poses)
        with pytest.raises(InvalidArgumentError, match="1 to 65600 futures"):
            predict_ensemble(runner, start, 10 * dt, 0)
        with pytest.raises(InvalidArgumentError, match="one plan per future"):
            predict_ensemble(runner, start, 10 * dt, 3, plans=[[], []])
        with pytest.raises(InvalidArgumentError):
            predict_ensemble(runner, Start(b"not a snapshot", "mujoco"), 10 * dt, 2)
        assert sorted(w.name for w in sim.list_worlds()) == [  # the refused blob's is gone
            "default", f"ensemble-{start.digest}", "side"]
    finally:
        runner.close()
    assert sorted(w.name for w in sim.list_worlds()) == ["default", "side"]
