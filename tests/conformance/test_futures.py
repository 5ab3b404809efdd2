"""Many futures in one prediction, the same on every engine: seeded perturbations give
differing futures and a spread, the same again for the same seed; no perturbation gives
copies of the single prediction bit for bit; plans, one per future, act at their times (a
plan imagined equals the plan executed live, bit for bit); a score per future; typed
refusals that change nothing."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support import snapshot
from support.models import KUKA_JOINTS, KUKA_KD, KUKA_KP, load_robot
from support.worlds import clean, contact_scene

from galton.client import Client, InvalidArgumentError, NotFoundError

STEPS = 30
EVERY = 10


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        yield client


def test_perturbed_futures_differ_spread_and_repeat_for_their_seed(world: Client) -> None:
    names = contact_scene(world)
    dt = world.status().timestep
    before = snapshot(world)
    ask = {"read": names, "futures": 4, "perturb": {"position": 0.001}, "seed": 1,
           "every": EVERY * dt}
    found = world.predict(STEPS * dt, **ask)
    before.assert_same(snapshot(world))
    samples = STEPS // EVERY + 1
    assert found.futures == 4 and found.seed == 1
    assert found.poses.shape == (4, samples, len(names), 7)
    assert found.spread is not None and found.spread.shape == (samples, len(names))
    assert np.all(found.spread > 0)
    assert not np.array_equal(found.poses[0], found.poses[1])
    positions = found.poses[:, :, :, :3]
    rms = np.sqrt(((positions - positions.mean(axis=0)) ** 2).sum(axis=3).mean(axis=0))
    np.testing.assert_allclose(found.spread, rms, rtol=1e-9)
    again = world.predict(STEPS * dt, **ask)
    np.testing.assert_array_equal(found.poses, again.poses)
    np.testing.assert_array_equal(found.twists, again.twists)


def test_a_batch_from_first_future_is_those_futures_of_the_whole_ensemble(
        world: Client) -> None:
    """Futures 2..4 of seed 7, asked as a batch, are futures 2..4 of the five at once."""
    names = contact_scene(world)
    dt = world.status().timestep
    ask = {"read": names, "perturb": {"position": 0.001, "velocity": 0.01}, "seed": 7,
           "every": EVERY * dt}
    whole = world.predict(STEPS * dt, futures=5, **ask)
    batch = world.predict(STEPS * dt, futures=3, first_future=2, **ask)
    assert batch.futures == 3 and batch.seed == 7
    np.testing.assert_array_equal(batch.poses, whole.poses[2:])
    np.testing.assert_array_equal(batch.twists, whole.twists[2:])
    with pytest.raises(InvalidArgumentError, match="first_future"):
        world.predict(STEPS * dt, futures=2, first_future=-1, **ask)


def test_unperturbed_futures_are_copies_of_the_single_prediction(world: Client) -> None:
    names = contact_scene(world)
    world.step(5)
    dt = world.status().timestep
    single = world.predict(STEPS * dt, read=names, every=EVERY * dt)
    many = world.predict(STEPS * dt, read=names, every=EVERY * dt, futures=3,
                         perturb={"position": 0.0})
    assert many.seed is None
    for future in range(3):
        np.testing.assert_array_equal(many.poses[future], single.poses)
        np.testing.assert_array_equal(many.twists[future], single.twists)
    assert many.spread is not None and not many.spread.any()


def test_a_plan_imagined_is_the_plan_executed_and_scores_pick_one(world: Client,
                                                                   engine: str) -> None:
    load_robot(world, "kuka")
    dt = world.status().timestep
    link = "lbr_iiwa_link_7"

    def plan(angle: float) -> list[dict[str, object]]:
        return [{"at": 0.0, "joint_targets": {
                    "names": KUKA_JOINTS[:2], "mode": "position", "targets": [angle, 0.3],
                    "kp": KUKA_KP[:2], "kd": KUKA_KD[:2]}},
                {"at": 10 * dt, "joint_targets": {
                    "names": KUKA_JOINTS[:2], "mode": "position", "targets": [-angle, 0.1],
                    "kp": KUKA_KP[:2], "kd": KUKA_KD[:2]}}]
    plans = [plan(0.4), plan(-0.4)]
    target = [0.3, 0.3, 1.0]
    found = world.predict(STEPS * dt, read=[link], read_joints=KUKA_JOINTS,
                          every=EVERY * dt, plans=plans, score={"body": link,
                                                                "target": target})
    assert found.futures == 2 and found.scores is not None and len(found.scores) == 2
    np.testing.assert_allclose(found.scores, np.linalg.norm(
        found.poses[:, -1, 0, :3] - np.array(target), axis=1), rtol=1e-12)
    assert not np.array_equal(found.poses[0], found.poses[1])
    assert [j.mode for j in world.joints()][:2] == ["none", "none"]  # nothing changed
    if engine not in ("mujoco", "pybullet"):
        return
    world.fork_world("live")  # the first plan, executed step by step
    live = world.world("live")
    live.set_joint_targets(**plans[0][0]["joint_targets"])  # type: ignore[arg-type]
    first = live.step_and_read_both(EVERY, [link], KUKA_JOINTS)
    live.set_joint_targets(**plans[0][1]["joint_targets"])  # type: ignore[arg-type]
    rest = [first, *(live.step_and_read_both(EVERY, [link], KUKA_JOINTS) for _ in range(2))]
    for k, (states, joints) in enumerate(rest, start=1):
        np.testing.assert_array_equal(found.poses[0, k], states.poses)
        np.testing.assert_array_equal(found.joint_positions[0, k], joints.positions)


def test_bad_futures_are_refused_and_change_nothing(world: Client) -> None:
    names = contact_scene(world)
    dt = world.status().timestep
    before = snapshot(world)
    step = {"at": 0.0, "wrenches": {"names": names[:1], "wrenches": [1, 0, 0, 0, 0, 0]}}
    with pytest.raises(InvalidArgumentError, match="one plan per future"):
        world.predict(STEPS * dt, read=names, futures=3, plans=[[step], [step]])
    with pytest.raises(InvalidArgumentError, match="past the horizon"):
        world.predict(STEPS * dt, read=names, plans=[[{**step, "at": 1e3}]])
    with pytest.raises(NotFoundError):
        world.predict(STEPS * dt, read=names, futures=2,
                      perturb={"bodies": {"nobody": {"position": 0.01}}})
    with pytest.raises(InvalidArgumentError, match="futures"):
        world.predict(STEPS * dt, read=names, futures=10_000)
    with pytest.raises(InvalidArgumentError, match="position"):
        world.predict(STEPS * dt, read=names, futures=2, perturb={"position": -1.0})
    before.assert_same(snapshot(world))


def test_compare_measures_an_observation_against_an_ensemble(world: Client,
                                                             engine: str) -> None:
    """The spread a prediction expected widens compare's position sigma: an observation
    1 cm off is a surprise against 1 mm of noise, not against a 5 cm spread."""
    if engine != "mujoco":
        pytest.skip("compare is the daemon's, not the engine's: one engine shows it")
    names = contact_scene(world)[:1]
    dt = world.status().timestep
    found = world.predict(STEPS * dt, read=names, futures=4, seed=3,
                          perturb={"position": 0.05})
    spread = found.spread_of(names)
    assert spread.shape == (1,) and spread[0] > 0
    world.step(STEPS)
    pose = world.get_states(names).poses.copy()
    pose[0, 0] += 0.01
    tight = world.compare(names, pose, sigma_position=0.001)
    loose = world.compare(names, pose, sigma_position=0.001, spread=spread)
    assert tight.score > 3 > loose.score
    expected = 0.01 / np.sqrt(spread[0] ** 2 + 0.001 ** 2)
    assert loose.score == pytest.approx(np.sqrt(expected ** 2 + loose.angle_errors[0] ** 2
                                                 / 0.05 ** 2), rel=1e-9)
    with pytest.raises(InvalidArgumentError, match="spread"):
        world.compare(names, pose, spread=-1.0)
