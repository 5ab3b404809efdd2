"""Rules every engine keeps alike, checked through the bridge: a stopped world replays its
first run bit for bit, set_states changes only what it is given, and a body sent absurdly
far faults the world (PHYSICS_ERROR) until a reset."""

from __future__ import annotations

import math

import numpy as np
import pytest

from galton.client import Client, body_group, boxes, plane, spheres
from galton.protocol import InvalidArgumentError

RADIUS = 0.05
FIRST_RUN_STEPS = 600


def turned(group: object, angles: list[float]) -> None:
    """Turn each body of a group about x by its angle (radians)."""
    poses = group.poses  # type: ignore[attr-defined]
    poses[:, 3] = np.sin(np.divide(angles, 2))
    poses[:, 6] = np.cos(np.divide(angles, 2))


def spawn_overlapping_scene(sim: Client) -> list[str]:
    """Spheres, boxes and a capsule made overlapping on a plane: they burst apart, collide
    and tumble, so whatever an engine kept of an earlier run shows within a few hundred
    steps (PyBullet kept contact points and their warm starts: 1e-5 m after 600 steps)."""
    balls = spheres([f"s{i}" for i in range(4)], [[0, 0, 0.05], [0.08, 0, 0.05],
                                                   [0.04, 0.06, 0.1], [0, 0.02, 0.14]], RADIUS)
    crates = boxes(["b0", "b1"], [[0.1, 0.05, 0.05], [0.14, 0.08, 0.09]], (0.05, 0.04, 0.03))
    turned(crates, [0.4, 0.7])
    pill = body_group("capsule", (0.03, 0.06), ["cap"], [[0.05, 0.1, 0.12]],
                      twists=np.array([[0.2, 0, 0, 0, 0, 1.0]]))
    turned(pill, [1.2])
    sim.spawn(plane(), balls, crates, pill)
    return [*balls.names, *crates.names, *pill.names]


def test_a_stopped_world_replays_its_first_run_whatever_ran_between(sim: Client) -> None:
    """Bit for bit after a stop, and after a shorter run and a second stop: nothing of a
    run (contact caches, warm starts) survives the rewind."""
    names = spawn_overlapping_scene(sim)
    created = sim.get_states(names)
    sim.step(FIRST_RUN_STEPS)
    first = sim.get_states(names)
    sim.stop()
    sim.step(100)
    sim.stop()
    sim.step(FIRST_RUN_STEPS)
    again = sim.get_states(names)
    np.testing.assert_array_equal(again.poses, first.poses)
    np.testing.assert_array_equal(again.twists, first.twists)
    assert np.abs(first.positions - created.positions).max() > 0.1  # they burst apart


def test_a_pose_alone_keeps_the_twist_and_a_twist_alone_the_pose(sim: Client) -> None:
    """Twists are in the world frame: turning a spinning body keeps its world spin (MuJoCo
    holds a free joint's spin in the body frame, so its engine writes it back)."""
    sim.spawn(boxes(["crate"], [[0, 0, 1]], (0.1, 0.1, 0.1),
                    twists=np.array([[1.0, 0, 2, 0, 3, 0]])))
    before = sim.get_states(["crate"])
    pose = np.array([[1, 1, 2, 0, 0, math.sin(0.2), math.cos(0.2)]])
    sim.set_states(["crate"], poses=pose)
    moved = sim.get_states(["crate"])
    np.testing.assert_allclose(moved.poses, pose, atol=1e-12)
    np.testing.assert_allclose(moved.twists, before.twists, atol=1e-12)
    twist = np.array([[0, 0, 0, 0, 0, 0.5]])
    sim.set_states(["crate"], twists=twist)
    spun = sim.get_states(["crate"])
    np.testing.assert_array_equal(spun.poses, moved.poses)
    np.testing.assert_allclose(spun.twists, twist, atol=1e-12)


def test_a_body_sent_absurdly_far_is_refused_and_the_world_goes_on(sim: Client) -> None:
    """A ball at x = 4e299 is finite (PyBullet would let it fall on there), but no
    simulation goes on from there: set_states refuses it, beyond the position limit, and
    nothing changes (issue 35: a state is refused when set, never faulted at a read)."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], RADIUS))
    with pytest.raises(InvalidArgumentError, match="position limit"):
        sim.set_states(["ball"], poses=np.array([[4e299, 0, 0.5, 0, 0, 0, 1]]))
    assert not sim.status().faulted
    np.testing.assert_array_equal(sim.get_states(["ball"]).positions, [[0, 0, 0.5]])
    sim.step(24)
    assert 0.4 < sim.get_states(["ball"]).positions[0, 2] < 0.5  # falling again
