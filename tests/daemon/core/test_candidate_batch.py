"""calibrate's candidates as one batch of futures (daemon/core/candidates.py), in process:
each candidate's error is exactly what a lone copy of the start with its values gives (the
path it replaced), gravity included (a world parameter, per future), a diverging candidate
costs only itself, and the start world is never touched."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from galton.daemon.core.candidates import CandidateBatch, Observation, position_error
from galton.daemon.core.fit_params import apply_values, parameters
from galton.daemon.core.limits import Limits
from galton.daemon.engines import create_engine
from galton.daemon.world.snapshot import clone_of
from galton.daemon.world.world import World
from galton.protocol.model import BodyGroup

LIMITS = Limits(max_speed=20.0, future_threads=2)
NAMES = ["box", "ball"]
STEPS = np.array([7, 30, 31, 60])


@pytest.fixture(params=["mujoco", "pybullet"])
def start(request: pytest.FixtureRequest) -> Iterator[World]:
    made = World(create_engine(request.param), "w", LIMITS)
    made.spawn([BodyGroup("plane", (5.0, 5.0), ["floor"], np.array([[0, 0, 0, 0, 0, 0, 1.0]]),
                          static=True, friction=1.0)])
    made.spawn([BodyGroup("box", (0.05, 0.05, 0.05), ["box"],
                          np.array([[0, 0, 0.05, 0, 0, 0, 1.0]]), mass=1.0, friction=0.5)])
    made.spawn([BodyGroup("sphere", (0.05,), ["ball"], np.array([[1, 0, 1.0, 0, 0, 0, 1.0]]),
                          mass=0.2, restitution=0.5)])
    made.set_states(["box"], made.get_states(["box"])[0], np.array([[1.5, 0, 0, 0, 0, 0]]))
    yield made
    made.engine.close()


def lone_error(start: World, fit: dict[str, list[float]], values: dict[str, float],
               seen: Observation) -> float:
    """The path the batch replaced: a copy of the start per candidate, stepped alone."""
    copy = clone_of(start, "lone", LIMITS)
    try:
        apply_values(copy, parameters(copy, fit), values)
        rows, done = [], 0
        for step in seen.steps:
            copy.step(int(step) - done)
            done = int(step)
            copy.verify()
            rows.append(copy.get_states(seen.names)[0][:, :3])
    finally:
        copy.engine.close()
    return position_error(np.array(rows), seen.positions)


def test_a_batch_scores_each_candidate_as_a_lone_copy_would(start: World) -> None:
    fit = {"box.friction": [0.1, 1.0], "ball.restitution": [0.0, 0.9],
           "gravity": [1.0, 20.0]}
    params = parameters(start, fit)
    seen = Observation(NAMES, STEPS, np.full((len(STEPS), 2, 3), 0.1))
    seen.positions[1, 0] = np.nan  # the box not seen once
    candidates = [{"box.friction": f, "ball.restitution": e, "gravity": g}
                  for f, e, g in [(0.2, 0.1, 9.81), (0.9, 0.8, 4.0), (0.5, 0.5, 15.0)]]
    before = start.get_states(NAMES)[0].copy()
    batch = CandidateBatch(start, params, candidates, seen, LIMITS, step_cost=1e-3)
    chunks = 0
    try:
        while not batch.finished:
            batch.advance()
            chunks += 1
    finally:
        batch.close()
    assert chunks > len(candidates) + len(STEPS)  # forks one by one, then small chunks
    expected = [lone_error(start, fit, values, seen) for values in candidates]
    np.testing.assert_allclose(batch.errors, expected, rtol=1e-12)
    assert len(set(batch.errors)) == 3  # the values (gravity too) differed per future
    np.testing.assert_array_equal(start.get_states(NAMES)[0], before)
    assert start.engine.get_params()["gravity"][2] == pytest.approx(-9.81)


def test_a_diverging_candidate_costs_only_itself(start: World) -> None:
    """At g = 1000 the ball passes max_speed (20 m/s) before it lands: sampled in flight
    (0.032 s, 32 m/s, 0.5 m down), that future has diverged; the others go on."""
    params = parameters(start, {"gravity": [1.0, 1000.0]})
    in_flight = round(0.032 / start.engine.timestep)
    steps = np.array([in_flight, *(in_flight + STEPS[1:] * 4)])
    seen = Observation(NAMES, steps, np.zeros((len(steps), 2, 3)))
    errors = CandidateBatch(start, params, [{"gravity": 9.81}, {"gravity": 1000.0},
                                            {"gravity": 5.0}], seen, LIMITS).run()
    assert np.isinf(errors[1])  # the ball fell faster than max_speed: diverged
    assert np.isfinite(errors[[0, 2]]).all() and errors[0] != errors[2]
