"""Several worlds per daemon and running ahead, the same on every engine: side worlds and
their refusals, a fork leaves its source as it would have been, a prediction equals stepping
a fork the same way (bit for bit) and never changes the world, compare's errors and score
against hand-computed values."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support import snapshot
from support.models import KUKA_JOINTS, KUKA_KD, KUKA_KP, load_robot
from support.worlds import clean, contact_scene

from galton.client import (
    Client,
    IncorrectStateError,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
    ResourceLimitError,
    Telemetry,
    spheres,
)

DEFAULT_MAX_WORLDS = 8  # docs/protocol.md, "Limits"
SAMPLE_STEPS = 10
SAMPLES = 12


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        yield client


def run(sim: Client, names: list[str]) -> np.ndarray:
    chunks = [sim.step_and_read(SAMPLE_STEPS, names) for _ in range(SAMPLES)]
    return np.stack([np.hstack([c.poses, c.twists]) for c in chunks])


# -- side worlds --------------------------------------------------------------------------
def test_side_worlds_are_listed_and_move_only_when_stepped(world: Client, engine: str) -> None:
    made = world.create_world("side")
    assert (made.name, made.live, made.engine, made.step, made.entity_count) == (
        "side", False, engine, 0, 0)
    side = world.world("side")
    side.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    side.step(10)
    assert side.status().step == 10
    rows = {w.name: w for w in world.list_worlds()}
    assert rows["default"].live and rows["default"].step == 0
    assert (rows["side"].step, rows["side"].entity_count) == (10, 1)
    assert world.list() == []  # the live world has none of it
    with pytest.raises(IncorrectStateError):
        side.play()
    world.delete_world("side")
    assert [w.name for w in world.list_worlds()] == ["default"]


def test_telemetry_has_a_sample_per_world(world: Client, engine: str) -> None:
    world.create_world("side")
    side = world.world("side")
    side.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    side.step(7)
    seen: dict[str, Telemetry] = {}
    with world.telemetry(timeout=5) as stream:
        for _ in range(40):  # 2 s at 10 Hz: a period holds one sample per world
            sample = stream.next(5)
            seen[sample.world] = sample
            if len(seen) == 2:
                break
    assert set(seen) == {"default", "side"}
    live, other = seen["default"], seen["side"]
    assert (live.step, live.entity_count) == (0, 0)
    assert (other.step, other.entity_count, other.state, other.engine) == (
        7, 1, "paused", engine)
    assert other.rtf == other.target_rtf == 0.0


def test_a_side_world_reply_carries_that_world_stamp(world: Client) -> None:
    world.create_world("side")
    side = world.world("side")
    side.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    assert side.step(10).step == 10
    assert side.get_states(["ball"]).step == 10
    assert world.status().step == 0  # the live world did not move


def test_world_refusals(world: Client) -> None:
    world.create_world("side")
    with pytest.raises(NameNotUniqueError):
        world.create_world("side")
    with pytest.raises(NameNotUniqueError):
        world.fork_world("side")
    with pytest.raises(InvalidArgumentError):
        world.delete_world("default")
    with pytest.raises(NotFoundError, match="side"):
        world.delete_world("sid")
    with pytest.raises(NotFoundError):
        world.fork_world("copy", source="nowhere")
    with pytest.raises(NotFoundError):
        world.world("nowhere").status()
    with pytest.raises(InvalidArgumentError):
        world.create_world("")


def test_worlds_past_the_limit_are_refused(world: Client) -> None:
    for i in range(DEFAULT_MAX_WORLDS - 1):
        world.create_world(f"w{i}")
    with pytest.raises(ResourceLimitError) as refused:
        world.fork_world("one_more")
    assert refused.value.details["limit"] == "max_worlds"
    assert len(world.list_worlds()) == DEFAULT_MAX_WORLDS


# -- fork ---------------------------------------------------------------------------------
def test_a_fork_does_not_disturb_its_source(world: Client) -> None:
    names = contact_scene(world)
    world.step(20)
    world.snapshot("start")
    world.restore("start")
    alone = run(world, names)
    world.restore("start")
    fork = world.fork_world("ahead")
    assert (fork.step, fork.entity_count) == (20, len(names) + 1)
    world.world("ahead").step(77)  # the fork runs on its own
    np.testing.assert_array_equal(run(world, names), alone)


def test_a_fork_goes_on_as_its_source_after_a_snapshot(world: Client) -> None:
    """A fork goes on as its source does after a snapshot (docs/protocol.md, "snapshot"):
    on MuJoCo the snapshot leaves the source as it was; on PyBullet it rebuilds it, and a
    fork starts from the same fresh contact caches."""
    names = contact_scene(world)
    world.step(20)
    world.fork_world("twin")
    world.snapshot(blob=True)
    np.testing.assert_array_equal(run(world.world("twin"), names), run(world, names))


# -- predict ------------------------------------------------------------------------------
def test_a_prediction_equals_stepping_a_fork_and_changes_nothing(world: Client) -> None:
    names = contact_scene(world)
    world.step(20)
    before = snapshot(world)
    dt = world.status().timestep
    found = world.predict(SAMPLES * SAMPLE_STEPS * dt, every=SAMPLE_STEPS * dt, read=names)
    before.assert_same(snapshot(world))
    assert found.steps == SAMPLES * SAMPLE_STEPS and len(found) == SAMPLES + 1
    assert found.poses.shape == (SAMPLES + 1, len(names), 7)
    assert found.twists.shape == (SAMPLES + 1, len(names), 6)
    assert (found.step, found.sim_time) == (before.step, found.times[0])
    present = world.get_states(names)
    np.testing.assert_array_equal(found.poses[0], present.poses)
    world.fork_world("twin")
    stepped = run(world.world("twin"), names)
    np.testing.assert_array_equal(np.concatenate([found.poses[1:], found.twists[1:]], axis=2),
                                  stepped)
    twin = world.world("twin").status()
    assert found.times[-1] == twin.sim_time


def test_a_prediction_with_changes_equals_a_fork_given_them(world: Client) -> None:
    load_robot(world, "kuka")
    world.set_joint_states(KUKA_JOINTS, np.linspace(-0.4, 0.4, 7))
    world.step(10)
    push = {"names": ["lbr_iiwa_link_7"], "wrenches": [3, 0, 0, 0, 0, 0.2]}
    targets = {"names": KUKA_JOINTS[:4], "mode": "position", "targets": [0.3, -0.2, 0.1, 0.4],
               "kp": KUKA_KP[:4], "kd": KUKA_KD[:4]}
    moved = {"names": ["lbr_iiwa_link_0"], "poses": [0, 0, 0.1, 0, 0, 0, 1]}
    before = snapshot(world)
    dt = world.status().timestep
    found = world.predict(100 * dt, every=20 * dt, read=["lbr_iiwa_link_7"],
                          read_joints=KUKA_JOINTS, joint_targets=targets, wrenches=push,
                          set_states=moved)
    before.assert_same(snapshot(world))
    assert [j.mode for j in world.joints()][:4] == ["none"] * 4
    world.fork_world("twin")
    twin = world.world("twin")
    twin.set_states(moved["names"], np.array([moved["poses"]]))
    twin.set_joint_targets(**targets)
    twin.apply_wrench(push["names"], push["wrenches"])
    for k in range(1, 6):
        states, joints = twin.step_and_read_both(20, ["lbr_iiwa_link_7"], KUKA_JOINTS)
        np.testing.assert_array_equal(found.poses[k], states.poses)
        np.testing.assert_array_equal(found.joint_positions[k], joints.positions)
        np.testing.assert_array_equal(found.joint_velocities[k], joints.velocities)


def test_a_prediction_from_a_slot_starts_there(world: Client) -> None:
    names = contact_scene(world)
    world.snapshot("zero")
    world.step(30)
    dt = world.status().timestep
    found = world.predict(5 * dt, read=names, slot="zero")
    assert found.times[0] == 0.0 and len(found) == 6
    assert world.status().step == 30


def test_samples_fall_every_whole_number_of_steps_from_the_present(world: Client) -> None:
    """every rounds to whole steps; the present is the first sample, and a horizon that is
    no multiple of every ends past the last sample."""
    names = contact_scene(world)
    world.step(4)
    status = world.status()
    dt = status.timestep
    found = world.predict(10 * dt, every=3.2 * dt, read=names[:1])
    assert found.steps == 10 and len(found) == 4
    world.fork_world("twin")
    twin = world.world("twin")
    for k in range(1, 4):
        reached = twin.step_and_read(3, names[:1])
        assert found.times[k] == twin.status().sim_time
        np.testing.assert_array_equal(found.poses[k], reached.poses)
    assert found.times[0] == status.sim_time
    every_step = world.predict(3 * dt, read=names[:1])
    assert len(every_step) == 4  # default: every step


def test_bad_predictions_are_refused_before_any_step(world: Client) -> None:
    names = contact_scene(world)
    before = snapshot(world)
    for bad in ({"horizon": 0.0}, {"horizon": -1.0}, {"horizon": float("nan")},
                {"horizon": 0.1, "every": 0.0}, {"horizon": 1e300}):
        with pytest.raises(InvalidArgumentError):
            world.call("predict", bad)
    with pytest.raises(NotFoundError):
        world.predict(0.1, read=["nothing"])
    with pytest.raises(NotFoundError):
        world.predict(0.1, slot="nothing")
    with pytest.raises(NotFoundError):
        world.predict(0.1, set_states={"names": ["nothing"], "poses": [0, 0, 0, 0, 0, 0, 1]})
    with pytest.raises(InvalidArgumentError):
        world.predict(0.1, read=names, wrenches={"names": names[:1], "wrenches": [np.nan] * 6})
    before.assert_same(snapshot(world))


# -- compare ------------------------------------------------------------------------------
def rotation_z(angle: float) -> list[float]:
    return [0.0, 0.0, float(np.sin(angle / 2)), float(np.cos(angle / 2))]


def test_compare_errors_and_score_as_computed_by_hand(world: Client) -> None:
    world.spawn(spheres(["a", "b"], [[0, 0, 1], [1, 0, 1]], 0.05, static=True))
    observed = np.array([[0.03, 0.04, 1.0, *rotation_z(0.1)], [1.0, 0.0, 1.0, 0, 0, 0, 1]])
    found = world.compare(["a", "b"], observed, sigma_position=0.01, sigma_angle=0.05)
    np.testing.assert_allclose(found.position_errors, [0.05, 0.0], atol=1e-12)
    np.testing.assert_allclose(found.angle_errors, [0.1, 0.0], atol=1e-9)
    assert found.score == pytest.approx(np.sqrt(((0.05 / 0.01) ** 2 + (0.1 / 0.05) ** 2) / 2))
    assert found.speed_errors is None and not found.corrected
    twists = np.array([[0.3, 0.4, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]])
    found = world.compare(["a", "b"], observed, twists, sigma_speed=0.5)
    assert found.speed_errors is not None
    np.testing.assert_allclose(found.speed_errors, [0.5, 0.0], atol=1e-12)
    assert found.score == pytest.approx(np.sqrt((25 + 4 + 1) / 2))


def test_compare_with_correct_moves_the_bodies(world: Client) -> None:
    world.spawn(spheres(["a"], [[0, 0, 1]], 0.05))
    observed = np.array([[0.2, 0.1, 0.8, *rotation_z(0.3)]])
    found = world.compare(["a"], observed, correct=True)
    assert found.corrected and found.score > 3
    np.testing.assert_allclose(world.get_states(["a"]).poses, observed, atol=1e-12)
    assert world.compare(["a"], observed).score == pytest.approx(0.0, abs=1e-6)


def test_compare_refusals_change_nothing(world: Client) -> None:
    world.spawn(spheres(["a"], [[0, 0, 1]], 0.05))
    before = snapshot(world)
    pose = np.array([0, 0, 1, 0, 0, 0, 1.0])
    with pytest.raises(NotFoundError):
        world.compare(["b"], pose, correct=True)
    for bad in ({"sigma_position": 0.0}, {"sigma_angle": -1.0}, {"sigma_speed": np.nan}):
        with pytest.raises(InvalidArgumentError):
            world.compare(["a"], pose, correct=True, **bad)
    with pytest.raises(InvalidArgumentError):
        world.call("compare", {"names": ["a"], "poses": b"\x00" * 8})
    with pytest.raises(InvalidArgumentError):
        world.compare(["a"], [np.nan, 0, 1, 0, 0, 0, 1], correct=True)
    before.assert_same(snapshot(world))
