"""The SDK's joint and wrench methods against real daemons, on both engines: loads with a
fixed or floating base, the joint table, joint states and targets as numpy arrays, reads
that ride on a step, wrenches, and bad input refused with typed errors, nothing applied."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pybullet_data
import pytest

from galton.client import (
    Client,
    InvalidArgumentError,
    JointInfo,
    JointStates,
    NotFoundError,
    Stamp,
    spheres,
)
from galton.client.sdk.joints import body_rows, joint_values, search_path_arg
from galton.daemon.engines.check.joints import RIG  # the checker's rig: base, hinge, slider, tip
from galton.protocol import unpack_f64

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
KUKA_JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]
FLANGE = "lbr_iiwa_link_7"


def load_kuka(sim: Client, **options: object) -> list[str]:
    return sim.load_model("urdf", text=KUKA.read_text(), search_path=[KUKA.parent],
                          **options)  # type: ignore[arg-type]


def by_name(joints: list[JointInfo]) -> dict[str, JointInfo]:
    return {joint.name: joint for joint in joints}


# -- loads and the joint table ----------------------------------------------------------
def test_a_fixed_base_urdf_is_a_model_with_links_and_joints(sim: Client) -> None:
    names = load_kuka(sim, prefix="k_")
    assert names == [f"k_lbr_iiwa_link_{i}" for i in range(8)]
    entities = {e.name: e for e in sim.list()}
    assert entities["k_lbr_iiwa_link_0"].shape == "model" and entities["k_lbr_iiwa_link_0"].static
    assert {e.model for e in entities.values()} == {"k_lbr_iiwa_link_0"}
    assert all(entities[n].shape == "link" for n in names[1:])
    joints = sim.joints()
    assert [j.name for j in joints] == [f"k_{n}" for n in KUKA_JOINTS]
    first = joints[0]
    assert (first.type, first.parent, first.child, first.mode) == (
        "revolute", "k_lbr_iiwa_link_0", "k_lbr_iiwa_link_1", "none")
    assert first.lower == pytest.approx(-2.96705972839) and first.upper is not None
    assert math.isclose(float(np.linalg.norm(first.axis)), 1.0)
    assert sim.joints(model="k_lbr_iiwa_link_0") == joints
    assert [j.name for j in sim.joints(names=["k_lbr_iiwa_joint_3"])] == ["k_lbr_iiwa_joint_3"]


def test_a_floating_base_has_a_free_joint_and_every_joint_type_is_listed(sim: Client) -> None:
    roots = sim.load_model("urdf", text=RIG, fixed_base=False)
    assert roots == ["base", "arm", "carriage", "tip"]
    joints = by_name(sim.joints())
    assert joints["base:free"].type == "free" and joints["base:free"].parent == ""
    assert joints["hinge"].type == "revolute" and joints["hinge"].axis == pytest.approx((0, 1, 0))
    assert joints["slider"].type == "prismatic"
    assert (joints["slider"].lower, joints["slider"].upper) == pytest.approx((-0.2, 0.4))
    assert joints["mount"].type == "fixed" and joints["mount"].child == "tip"
    assert not sim.list("base")[0].static


# -- joint states -------------------------------------------------------------------------
def test_joint_states_round_trip_as_arrays_and_scalars(sim: Client) -> None:
    load_kuka(sim)
    positions = np.linspace(-0.6, 0.6, 7)
    velocities = np.linspace(0.5, -0.5, 7)
    stamp = sim.set_joint_states(KUKA_JOINTS, positions, velocities)
    assert isinstance(stamp, Stamp) and stamp.step == 0
    states = sim.get_joint_states(KUKA_JOINTS)
    assert isinstance(states, JointStates) and states.names == KUKA_JOINTS
    np.testing.assert_allclose(states.positions, positions, atol=1e-9)
    np.testing.assert_allclose(states.velocities, velocities, atol=1e-9)
    np.testing.assert_array_equal(states.efforts, np.zeros(7))  # mode none: no effort
    assert states.stamp == Stamp(0, 0.0)
    sim.set_joint_states(KUKA_JOINTS[:3], 0.25)  # one number for every joint, velocity kept
    again = sim.get_joint_states()  # every 1-DOF joint
    assert again.names == KUKA_JOINTS
    np.testing.assert_allclose(again.positions[:3], 0.25, atol=1e-9)
    np.testing.assert_allclose(again.velocities, velocities, atol=1e-9)


def test_a_position_target_is_reached_and_shown(sim: Client) -> None:
    sim.set_params({"timestep": 0.001})  # an explicit PD law on a light wrist: a short step
    load_kuka(sim)
    target = np.array([0.4, 0.6, -0.3, -1.2, 0.5, 0.8, -0.6])  # away from singular poses
    sim.set_joint_targets(KUKA_JOINTS, "position", target,
                          kp=[2000, 2000, 1000, 1000, 100, 50, 10],
                          kd=[100, 100, 50, 50, 5, 2, 0.3], max_effort=300.0)
    assert {j.mode for j in sim.joints()} == {"position"}
    states = sim.run_until_and_read_joints(1.5, KUKA_JOINTS)
    assert states.sim_time >= 1.5
    np.testing.assert_allclose(states.positions, target, atol=0.05)
    assert np.all(np.abs(states.efforts) <= 300.0 + 1e-9) and np.any(states.efforts != 0)
    sim.set_joint_targets(KUKA_JOINTS, "none")
    assert {j.mode for j in sim.joints()} == {"none"}


def test_a_step_reads_joints_and_links_in_one_reply(sim: Client) -> None:
    load_kuka(sim)
    sim.set_joint_states(KUKA_JOINTS, 0.1)
    joints = sim.step_and_read_joints(3, KUKA_JOINTS[:2])
    assert joints.names == KUKA_JOINTS[:2] and joints.step == 3
    states, both = sim.step_and_read_both(2, [FLANGE], KUKA_JOINTS)
    assert states.names == [FLANGE] and both.names == KUKA_JOINTS
    assert states.stamp == both.stamp == Stamp(5, both.sim_time)
    assert states.positions[0, 2] > 0.5  # the flange is up there, not at the base


def test_reset_state_puts_joints_back_and_targets_off(sim: Client) -> None:
    load_kuka(sim)
    sim.set_joint_targets(KUKA_JOINTS[:2], "velocity", 0.5, kd=5.0)
    sim.step(50)
    sim.reset("state")
    states = sim.get_joint_states(KUKA_JOINTS)
    np.testing.assert_array_equal(states.positions, np.zeros(7))
    assert {j.mode for j in sim.joints()} == {"none"}


# -- wrenches -----------------------------------------------------------------------------
def test_a_wrench_pushes_a_free_body_until_its_duration_ends(sim: Client) -> None:
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    sim.spawn(spheres(["ball"], [[0, 0, 1]], radius=0.1, mass=2.0))
    timestep = float(sim.get_params()["timestep"])
    sim.apply_wrench(["ball"], [4.0, 0, 0, 0, 0, 0], duration=10 * timestep)
    pushed = sim.step_and_read(20, ["ball"]).twists[0]
    assert pushed[0] == pytest.approx(4.0 / 2.0 * 10 * timestep, rel=0.01)  # v = F/m t
    sim.apply_wrench(["ball"], np.array([[0, 2.0, 0, 0, 0, 0]]))
    assert sim.step_and_read(1, ["ball"]).twists[0, 1] > 0
    sim.clear_wrenches(["ball"])
    held = sim.step_and_read(1, ["ball"]).twists[0, 1]
    assert sim.step_and_read(5, ["ball"]).twists[0, 1] == pytest.approx(held)
    assert isinstance(sim.clear_wrenches(), Stamp)


# -- bad input: typed errors, nothing applied ---------------------------------------------
def test_an_unknown_joint_is_not_found_with_a_suggestion(sim: Client) -> None:
    load_kuka(sim)
    with pytest.raises(NotFoundError, match="did you mean 'lbr_iiwa_joint_"):
        sim.get_joint_states(["lbr_iiwa_joint_l"])
    with pytest.raises(NotFoundError, match="did you mean"):
        sim.set_joint_targets(["lbr_iiwa_jiont_2"], "position", 0.1, kp=10.0)
    with pytest.raises(NotFoundError, match="did you mean"):
        sim.joints(names=["lbr_iiwa_joint_9"])


@pytest.mark.parametrize("bad", [{"kp": math.nan}, {"kd": [1, 1, math.nan, 1, 1, 1, 1]},
                                 {"kp": -1.0}, {"max_effort": 0.0}],
                         ids=["nan-kp", "nan-kd", "negative-kp", "zero-max-effort"])
def test_bad_gains_are_invalid_and_nothing_is_applied(sim: Client,
                                                     bad: dict[str, object]) -> None:
    load_kuka(sim)
    gains: dict[str, object] = {"kp": 100.0, "kd": 1.0, **bad}
    with pytest.raises(InvalidArgumentError):
        sim.set_joint_targets(KUKA_JOINTS, "position", 0.1, **gains)  # type: ignore[arg-type]
    assert {j.mode for j in sim.joints()} == {"none"}


def test_targets_and_states_refuse_fixed_and_free_joints(sim: Client) -> None:
    sim.load_model("urdf", text=RIG, fixed_base=False)
    with pytest.raises(InvalidArgumentError, match="mount"):
        sim.set_joint_targets(["hinge", "mount"], "position", 0.1, kp=10.0)
    with pytest.raises(InvalidArgumentError):
        sim.get_joint_states(["base:free"])
    with pytest.raises(InvalidArgumentError):
        sim.step_and_read_joints(1, ["mount"])
    assert sim.status().step == 0  # refused before any step
    assert by_name(sim.joints())["hinge"].mode == "none"


def test_out_of_limit_positions_and_wrong_counts_are_invalid(sim: Client) -> None:
    sim.load_model("urdf", text=RIG)
    with pytest.raises(InvalidArgumentError, match="slider"):
        sim.set_joint_states(["hinge", "slider"], [0.1, 0.9])
    with pytest.raises(InvalidArgumentError):
        sim.set_joint_states(["hinge", "slider"], [0.1, 0.2, 0.3])
    np.testing.assert_array_equal(sim.get_joint_states(["hinge", "slider"]).positions, 0.0)


def test_a_wrench_on_a_fixed_base_or_of_a_bad_width_is_invalid(sim: Client) -> None:
    load_kuka(sim)
    with pytest.raises(InvalidArgumentError, match="lbr_iiwa_link_0"):
        sim.apply_wrench(["lbr_iiwa_link_0"], [1.0, 0, 0, 0, 0, 0])
    with pytest.raises(InvalidArgumentError, match="rows of 6"):
        sim.apply_wrench([FLANGE], [1.0, 0, 0])  # refused before any request
    with pytest.raises(InvalidArgumentError, match="must be numbers"):
        sim.set_joint_states(KUKA_JOINTS, "half")  # type: ignore[arg-type]


# -- wire arguments (no daemon) -----------------------------------------------------------
def test_values_and_rows_are_packed_float64_with_broadcasting() -> None:
    assert unpack_f64(joint_values(0.5, 3, "kp"), 1)[:, 0].tolist() == [0.5, 0.5, 0.5]
    assert unpack_f64(joint_values(np.arange(3), 3, "kp"), 1)[:, 0].tolist() == [0, 1, 2]
    tiled = unpack_f64(body_rows([1, 2, 3], 2, 3, "points"), 3)
    assert tiled.tolist() == [[1, 2, 3], [1, 2, 3]]
    with pytest.raises(InvalidArgumentError):
        body_rows(np.zeros((2, 4)), 2, 3, "points")
    assert search_path_arg([Path("/a"), "/b"]) == "/a:/b"
    assert search_path_arg("/a:/b") == "/a:/b"


def test_set_joint_states_reads_links_where_the_joints_put_them(sim: Client) -> None:
    load_kuka(sim)
    seen = sim.set_joint_states_and_read(KUKA_JOINTS, 0.4, [FLANGE])
    assert seen.names == [FLANGE]
    np.testing.assert_array_equal(seen.poses, sim.get_states([FLANGE]).poses)
    assert seen.step == sim.status().step  # no step was taken
    before = sim.get_joint_states(KUKA_JOINTS).positions
    with pytest.raises(NotFoundError, match="lbr_iiwa_link_7"):
        sim.set_joint_states_and_read(KUKA_JOINTS, 0.0, ["lbr_iiwa_link_77"])
    np.testing.assert_array_equal(sim.get_joint_states(KUKA_JOINTS).positions, before)
