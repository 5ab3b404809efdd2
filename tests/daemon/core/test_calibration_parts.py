"""calibrate's pure parts: the CMA-ES search, and the start's twists estimated from the
first samples (exact under constant acceleration, as the engines integrate it)."""

from __future__ import annotations

import numpy as np
import pytest

from galton.daemon.core.cmaes import CmaEs, default_population
from galton.daemon.core.observations import observation, sample_poses, start_twists
from galton.protocol import InvalidArgumentError, pack_f64


def test_cma_es_finds_a_valley_inside_the_box() -> None:
    target = np.array([0.2, 0.7, 0.45])
    search = CmaEs(np.array([0.9, 0.1, 0.5]), 0.3, default_population(3),
                   np.random.default_rng(1))
    for _ in range(80):
        points = search.ask()
        assert ((points >= 0) & (points <= 1)).all()
        search.tell(points, ((points - target) ** 2 * [1, 10, 100]).sum(axis=1))
        if search.converged:
            break
    assert search.converged
    np.testing.assert_allclose(search.mean, target, atol=2e-3)


def test_cma_es_is_seeded() -> None:
    first, second = (CmaEs(np.zeros(2), 0.3, 6, np.random.default_rng(5)) for _ in range(2))
    np.testing.assert_array_equal(first.ask(), second.ask())


def test_start_twists_are_exact_under_constant_acceleration() -> None:
    """Semi-implicit Euler (velocity, then position with it), sampled at uneven steps."""
    dt, v, p = 0.002, np.array([1.5, 0.0, -0.98]), np.array([0.0, 0.0, 1.0])
    a = np.array([-2.94, 0.0, -9.81])
    positions, velocity, position = [p.copy()], v.copy(), p.copy()
    for _ in range(20):
        velocity = velocity + a * dt
        position = position + velocity * dt
        positions.append(position.copy())
    steps = [0, 7, 15]
    poses = np.zeros((3, 1, 7))
    poses[:, 0, :3] = [positions[s] for s in steps]
    poses[:, 0, 6] = 1.0
    twists = start_twists(np.array(steps) * dt, poses, dt)
    np.testing.assert_allclose(twists[0, :3], v, atol=1e-9)
    np.testing.assert_allclose(twists[0, 3:], 0.0, atol=1e-12)


def test_a_turning_body_gets_its_angular_velocity() -> None:
    rate, seconds = 2.0, 0.01  # rad/s about z
    half = rate * seconds / 2
    poses = np.zeros((2, 1, 7))
    poses[0, 0, 6] = 1.0
    poses[1, 0, 5:] = [np.sin(half), np.cos(half)]
    twists = start_twists(np.array([0.0, seconds]), poses, 0.001)
    np.testing.assert_allclose(twists[0, 3:], [0.0, 0.0, rate], atol=1e-9)


def test_samples_are_checked() -> None:
    rows = np.tile([0, 0, 0, 0, 0, 0, 1.0], (2, 1))
    rows[1] = np.nan  # not seen in the second sample: allowed
    assert np.isnan(sample_poses(pack_f64(rows), 2, 1)[1]).all()
    with pytest.raises(InvalidArgumentError, match="first sample"):
        sample_poses(pack_f64(rows[::-1]), 2, 1)
    with pytest.raises(InvalidArgumentError, match="cannot be told apart"):
        observation(["a"], np.array([0.0, 0.0004, 0.01]), np.zeros((3, 1, 7)), 0.002)
