"""Joints through a real daemon, the same on every engine: joint states, reads on a step,
targets and their modes, stop and reset, wrenches, and what a bad request leaves (nothing
changed)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from support.models import (
    KUKA_JOINTS,
    KUKA_KD,
    KUKA_KP,
    Pendulum,
    apply_wrench,
    get_joint_states,
    joints,
    load,
    load_robot,
    model_snapshot,
    set_joint_states,
    set_targets,
    step_joints,
)

from galton.client import Client, body_group, spheres
from galton.protocol import InvalidArgumentError, NotFoundError


def test_joint_states_round_trip(sim: Client) -> None:
    load_robot(sim, "kuka")
    rng = np.random.default_rng(24)
    positions, velocities = rng.uniform(-1, 1, 7), rng.uniform(-2, 2, 7)
    set_joint_states(sim, KUKA_JOINTS, positions, velocities)
    read = get_joint_states(sim, KUKA_JOINTS)
    assert read.names == KUKA_JOINTS
    np.testing.assert_allclose(read.positions, positions, atol=1e-12)
    np.testing.assert_allclose(read.velocities, velocities, atol=1e-12)
    np.testing.assert_array_equal(read.efforts, 0.0)
    set_joint_states(sim, KUKA_JOINTS[:2], 0.25)  # one number for all; velocities kept
    read = get_joint_states(sim, KUKA_JOINTS[:2])
    np.testing.assert_allclose(read.positions, 0.25, atol=1e-12)
    np.testing.assert_allclose(read.velocities, velocities[:2], atol=1e-12)



def test_every_scalar_joint_is_read_when_no_names_are_given(sim: Client) -> None:
    load_robot(sim, "r2d2")
    scalar = [j.name for j in joints(sim) if j.type in ("revolute", "prismatic")]
    assert sorted(get_joint_states(sim).names) == sorted(scalar)



def test_a_link_pose_follows_its_joint(sim: Client) -> None:
    load(sim, "urdf", text=Pendulum().urdf())
    set_joint_states(sim, ["hinge"], np.pi / 2)
    pose = sim.get_states(["bob"]).poses[0]
    np.testing.assert_allclose(pose[:3], [0, 0, 2], atol=1e-9)  # the link frame: the pivot
    # a quarter turn about y, scalar last, qw >= 0
    np.testing.assert_allclose(pose[3:], [0, np.sqrt(0.5), 0, np.sqrt(0.5)], atol=1e-9)



def test_step_reads_joints_in_the_same_reply(sim: Client) -> None:
    load_robot(sim, "kuka")
    set_joint_states(sim, KUKA_JOINTS, 0.3)
    stepped = step_joints(sim, 5, KUKA_JOINTS)
    assert sim.status().step == 5
    read = get_joint_states(sim, KUKA_JOINTS)
    assert stepped.names == read.names == KUKA_JOINTS
    for key in ("positions", "velocities", "efforts"):
        np.testing.assert_array_equal(getattr(stepped, key), getattr(read, key))
    assert np.abs(stepped.velocities).max() > 0  # gravity moved the arm



def test_run_until_reads_joints(sim: Client) -> None:
    load_robot(sim, "kuka")
    result = sim.call("run_until", {"sim_time": 0.05, "read_joints": KUKA_JOINTS[:3]})
    assert list(result["joints"]["names"]) == KUKA_JOINTS[:3]



def _drive(sim: Client) -> np.ndarray:
    """Joint states set, position targets on some joints, a wrench on a link: 200 steps."""
    set_joint_states(sim, KUKA_JOINTS, np.linspace(-0.5, 0.5, 7), 0.1)
    set_targets(sim, KUKA_JOINTS[:4], "position", [0.4, -0.3, 0.2, 0.5], kp=KUKA_KP[:4],
                kd=KUKA_KD[:4])
    set_targets(sim, KUKA_JOINTS[4:], "effort", [0.5, -0.5, 0.2])
    apply_wrench(sim, ["lbr_iiwa_link_7"], [[5, 0, 0, 0, 0, 0.3]])
    read = step_joints(sim, 200, KUKA_JOINTS)
    poses = sim.get_states().poses
    return np.concatenate([read.positions, read.velocities, read.efforts, poses.ravel()])



@pytest.mark.parametrize("how", ["stop", "reset-state"])
def test_stop_and_reset_restore_joints_and_release_targets(sim: Client, how: str) -> None:
    load_robot(sim, "kuka")
    initial = model_snapshot(sim)
    first = _drive(sim)
    if how == "stop":
        sim.stop()
    else:
        sim.reset("state")
        sim.reset("time")
    assert {j.mode for j in joints(sim)} == {"none"}
    read = get_joint_states(sim, KUKA_JOINTS)
    np.testing.assert_array_equal(read.positions, initial.states.positions)
    np.testing.assert_array_equal(read.velocities, 0.0)
    np.testing.assert_array_equal(read.efforts, 0.0)
    np.testing.assert_array_equal(sim.get_states().poses, initial.scene.poses)
    second = _drive(sim)
    np.testing.assert_array_equal(second, first)  # bit-identical replay



def test_released_joints_swing_freely_after_stop(sim: Client) -> None:
    load(sim, "urdf", text=Pendulum().urdf())
    set_joint_states(sim, ["hinge"], 0.5)
    set_targets(sim, ["hinge"], "position", 0.5, kp=500, kd=10)
    sim.step(50)
    sim.stop()
    set_joint_states(sim, ["hinge"], 0.5)
    read = step_joints(sim, round(0.3 / sim.status().timestep), ["hinge"])
    assert read.positions[0] < 0.4 and read.efforts[0] == 0.0  # gravity alone



def test_unknown_joint_is_not_found_with_a_suggestion(sim: Client) -> None:
    load_robot(sim, "kuka")
    before = model_snapshot(sim)
    for op, args in (("get_joint_states", {}), ("set_joint_states", {"positions": 0.1}),
                     ("set_joint_targets", {"mode": "effort", "targets": 1.0}),
                     ("joints", {})):
        with pytest.raises(NotFoundError, match="did you mean 'lbr_iiwa_joint_1'") as error:
            sim.call(op, {"names": ["lbr_iiwa_joint_1", "lbr_iiwa_jiont_1"], **args})
        assert error.value.details["missing"] == ["lbr_iiwa_jiont_1"]
    with pytest.raises(NotFoundError):
        step_joints(sim, 1, ["nope"])
    model_snapshot(sim).assert_same(before)



def test_a_target_on_a_fixed_joint_is_invalid(sim: Client) -> None:
    load_robot(sim, "panda")
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="panda_joint8"):
        set_targets(sim, ["panda_joint1", "panda_joint8"], "effort", 1.0)
    with pytest.raises(InvalidArgumentError, match="panda_joint8"):
        get_joint_states(sim, ["panda_joint8"])
    model_snapshot(sim).assert_same(before)



@pytest.mark.parametrize("gains", [
    {"kp": float("nan"), "kd": 1.0}, {"kp": 10.0, "kd": float("nan")},
    {"kp": [10.0, float("nan")], "kd": 1.0}, {"kp": 10.0, "max_effort": float("nan")},
    {"kp": -1.0}, {"kp": 0.0}, {"kp": 10.0, "max_effort": 0.0},
], ids=["kp-nan", "kd-nan", "kp-nan-packed", "max-effort-nan", "kp-negative", "kp-zero",
        "max-effort-zero"])
def test_bad_gains_are_invalid_and_apply_nothing(sim: Client, gains: dict[str, Any]) -> None:
    load_robot(sim, "kuka")
    set_targets(sim, KUKA_JOINTS[:2], "effort", 2.0)
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError):
        set_targets(sim, KUKA_JOINTS[:2], "position", 0.1, **gains)
    model_snapshot(sim).assert_same(before)
    assert step_joints(sim, 1, KUKA_JOINTS[:2]).efforts.tolist() == [2.0, 2.0]



def test_bad_targets_and_states_are_invalid(sim: Client) -> None:
    load_robot(sim, "kuka")
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="limits"):
        set_joint_states(sim, KUKA_JOINTS[:1], 3.5)
    with pytest.raises(InvalidArgumentError, match="limits"):
        set_targets(sim, KUKA_JOINTS[:1], "position", 3.5, kp=10.0)
    with pytest.raises(InvalidArgumentError):
        set_joint_states(sim, KUKA_JOINTS, [0.1, 0.2])  # wrong count
    with pytest.raises(InvalidArgumentError):
        set_targets(sim, KUKA_JOINTS[:1], "velocity", 1.0)  # kd = 0
    model_snapshot(sim).assert_same(before)



def test_a_wrench_on_a_fixed_base_is_invalid(sim: Client) -> None:
    load_robot(sim, "kuka")
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="lbr_iiwa_link_0"):
        apply_wrench(sim, ["lbr_iiwa_link_0"], [[1, 0, 0, 0, 0, 0]])
    with pytest.raises(InvalidArgumentError):
        apply_wrench(sim, ["lbr_iiwa_link_7"], [[float("nan"), 0, 0, 0, 0, 0]])
    model_snapshot(sim).assert_same(before)



def _push(sim: Client, groups: list[int], duration_steps: int | None) -> np.ndarray:
    """A 2 kg ball pushed along x (for ``duration_steps`` steps, or until cleared after
    10), stepped in these groups of steps; its state after them."""
    dt = sim.status().timestep
    duration = None if duration_steps is None else duration_steps * dt
    apply_wrench(sim, ["ball"], [[4, 0, 0, 0, 0, 0]], duration=duration)
    for i, count in enumerate(groups):
        if duration_steps is None and i == 1:
            sim.call("clear_wrenches", {"names": ["ball"]})
        sim.step(count)
    states = sim.get_states(["ball"])
    return np.concatenate([states.poses[0], states.twists[0]])



def test_a_wrench_duration_ends_on_its_exact_step(sim: Client) -> None:
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    sim.spawn(body_group("sphere", (0.1,), ["ball"], [[0, 0, 1]], mass=2.0))
    cleared = _push(sim, [10, 5], None)  # held, cleared by hand after exactly 10 steps
    for groups in ([15], [3, 3, 3, 3, 3], [1] * 15, [9, 6]):
        sim.stop()
        np.testing.assert_array_equal(_push(sim, groups, 10), cleared, err_msg=str(groups))
    sim.stop()
    longer = _push(sim, [15], 11)
    assert longer[7] > cleared[7]  # one more step of push: faster



def test_joints_show_the_mode_they_hold(sim: Client) -> None:
    load_robot(sim, "kuka")
    set_targets(sim, KUKA_JOINTS[:2], "position", 0.1, kp=10.0)
    set_targets(sim, KUKA_JOINTS[2:3], "velocity", 0.1, kd=1.0)
    set_targets(sim, KUKA_JOINTS[3:4], "effort", 0.5)
    modes = [j.mode for j in joints(sim, names=KUKA_JOINTS)]
    assert modes == ["position", "position", "velocity", "effort", "none", "none", "none"]
    set_targets(sim, KUKA_JOINTS[:1], "none")
    assert joints(sim, names=KUKA_JOINTS[:1])[0].mode == "none"
    assert step_joints(sim, 1, KUKA_JOINTS[:1]).efforts[0] == 0.0



def _held_run(sim: Client, churn: bool) -> np.ndarray:
    """Targets and a wrench held for 100 steps; between steps 50 and 51, when ``churn``,
    5,000 static spheres spawned and deleted (PyBullet rebuilds its world past 5,000
    removals and must carry joint states, targets and wrenches)."""
    load_robot(sim, "kuka")
    set_joint_states(sim, KUKA_JOINTS, np.linspace(-0.4, 0.4, 7), 0.2)
    set_targets(sim, KUKA_JOINTS, "position", 0.3, kp=KUKA_KP, kd=KUKA_KD)
    apply_wrench(sim, ["lbr_iiwa_link_5"], [[0, 10, 0, 0, 0, 0]])
    sim.step(50)
    if churn:
        names = [f"s{i}" for i in range(5000)]
        sim.spawn(spheres(names, np.column_stack([np.arange(5000) * 0.3, np.full(5000, 50.0),
                                                  np.zeros(5000)]), 0.1, static=True))
        sim.delete(names)
    read = step_joints(sim, 50, KUKA_JOINTS)
    return np.concatenate([read.positions, read.velocities, read.efforts])



def test_a_rebuild_carries_joint_states_targets_and_wrenches(sim: Client) -> None:
    quiet = _held_run(sim, churn=False)
    sim.reset("all")
    np.testing.assert_array_equal(_held_run(sim, churn=True), quiet)

