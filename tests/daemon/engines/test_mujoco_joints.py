"""Joints, targets and wrenches in the MuJoCo engine on its own: the PD law as applied,
clipping, limits, and physics checked against closed forms (pendulum period, F = m a,
holding torque m g d), and what survives recompiles, teleports and restores.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import pybullet_data
import pytest

from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.daemon.world.model_files import resolve_model
from galton.protocol import BodyGroup

DATA = Path(pybullet_data.getDataPath())
KUKA = "kuka_iiwa/model.urdf"
GRAVITY = 9.81
INF = np.full(1, np.inf)
ONE, ZERO = np.ones(1), np.zeros(1)
# A point-ish bob (1 kg sphere of 2 cm) on a light rod (1 m capsule of density 1), hinged
# about y at its top; and the same link held out horizontally along x.
PENDULUM = """<mujoco><worldbody>
<body name="pivot" pos="0 0 2"><geom type="box" size=".02 .02 .02" contype="0"
  conaffinity="0"/>
 <body name="bob"><joint name="swing" type="hinge" axis="0 1 0"/>
  <geom type="capsule" fromto="0 0 0 {x} 0 {z}" size=".005" density="1" contype="0"
   conaffinity="0"/>
  <geom type="sphere" pos="{x} 0 {z}" size=".02" mass="1" contype="0" conaffinity="0"/>
 </body></body>
</worldbody></mujoco>"""
HANGING = PENDULUM.format(x=0, z=-1)
HORIZONTAL = PENDULUM.format(x=1, z=0)


def urdf_text(relative: str) -> str:
    """The URDF as the daemon hands it over: its mesh file names absolute."""
    path = DATA / relative
    return resolve_model("urdf", path.read_text(), str(path), [])


@pytest.fixture
def engine() -> MujocoEngine:
    return MujocoEngine()


def kuka(engine: MujocoEngine) -> list[str]:
    """kuka_iiwa, fixed, integrated implicitly in velocity: its light distal links under a
    stiff PD diverge with explicit Euler at the 2 ms step."""
    engine.set_params({"mujoco.integrator": "implicitfast"})
    engine.load_model("urdf", urdf_text(KUKA), None, "k/")
    return [j.name for j in engine.joints()]


def about_the_hinge(engine: MujocoEngine, body: str) -> tuple[float, float, float]:
    """Mass, distance of the centre of mass from the hinge (at the body's origin, about y),
    and moment of inertia about the hinge, from the compiled model."""
    m, b = engine.model, engine.ids[body]
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, m.body_iquat[b])
    rotation = rotation.reshape(3, 3)
    inertia = rotation @ np.diag(m.body_inertia[b]) @ rotation.T
    mass, (x, _, z) = float(m.body_mass[b]), m.body_ipos[b]
    return mass, math.hypot(x, z), float(inertia[1, 1] + mass * (x * x + z * z))


def test_a_pendulums_small_swing_has_the_compound_pendulum_period(
        engine: MujocoEngine) -> None:
    """T = 2 pi sqrt(I / (m g d)) within 1 % (measured: 2e-5) at 0.02 rad, over 5 periods."""
    engine.load_model("mjcf", HANGING, None, "p/")
    mass, distance, inertia = about_the_hinge(engine, "p/bob")
    period = 2 * math.pi * math.sqrt(inertia / (mass * GRAVITY * distance))
    engine.set_joint_states(["p/swing"], np.array([0.02]), ZERO)
    angles = []
    for _ in range(round(5 * period / engine.timestep)):
        engine.step(1)
        angles.append(engine.get_joint_states(["p/swing"])[0][0])
    q = np.array(angles)
    down = np.flatnonzero((q[:-1] > 0) & (q[1:] <= 0))
    crossings = (down + q[down] / (q[down] - q[down + 1])) * engine.timestep
    assert np.mean(np.diff(crossings)) == pytest.approx(period, rel=0.01)


@pytest.mark.parametrize("point", [None, (0.0, 0.0, 1.0)])
def test_a_wrench_on_a_free_body_gives_f_over_m(engine: MujocoEngine,
                                                point: tuple[float, ...] | None) -> None:
    engine.set_params({"gravity": [0, 0, 0]})
    engine.spawn([BodyGroup(shape="box", size=(0.1, 0.2, 0.3), names=["b"], mass=2.0,
                            poses=np.array([[0, 0, 1, 0, 0, 0, 1.0]]))])
    force = np.array([3.0, -1.0, 0.5])
    engine.set_wrenches(["b"], np.array([[*force, 0, 0, 0]]),
                        None if point is None else np.array([point]))
    engine.step(500)
    _, twists = engine.get_states(["b"])
    np.testing.assert_allclose(twists[0, :3] / (500 * engine.timestep), force / 2.0, rtol=0.01)
    np.testing.assert_allclose(twists[0, 3:], 0.0, atol=1e-12)


def test_a_wrench_off_the_centre_turns_and_is_held_until_cleared(engine: MujocoEngine) -> None:
    engine.set_params({"gravity": [0, 0, 0]})
    engine.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["b"], mass=2.0,
                            poses=np.array([[0, 0, 1, 0, 0, 0, 1.0]]))])
    engine.set_wrenches(["b"], np.array([[0, 1.0, 0, 0, 0, 0]]), np.array([[0.1, 0, 1.0]]))
    engine.spawn([BodyGroup(shape="box", size=(0.1, 0.1, 0.1), names=["c"], mass=3.0,
                            poses=np.array([[2, 0, 1, 0, 0, 0, 1.0]]))])  # a recompile
    engine.step(10)
    _, twists = engine.get_states(["b", "c"])
    spin = 0.1 * 1.0 / (0.4 * 2.0 * 0.1**2)  # torque / (2/5 m r^2)
    assert twists[0, 5] / (10 * engine.timestep) == pytest.approx(spin, rel=1e-6)
    assert not twists[1].any()
    engine.clear_wrenches(["b"])
    engine.step(10)
    np.testing.assert_allclose(engine.get_states(["b"])[1], twists[:1], rtol=1e-12)


def test_targets_apply_the_pd_law_exactly_and_clip(engine: MujocoEngine) -> None:
    """The stiffness part at the step's start, clipped; the damping implicit: at the
    velocity the step ends with, unclipped (module docstring of mujoco_joints)."""
    names = kuka(engine)
    n = len(names)
    target, kp, kd = np.linspace(-0.5, 0.5, n), np.full(n, 300.0), np.full(n, 20.0)
    engine.set_joint_targets(names, "position", target, kp, kd, np.full(n, np.inf))
    for _ in range(3):
        q = engine.get_joint_states(names)[0]
        engine.step(1)
        _, qd, effort = engine.get_joint_states(names)
        np.testing.assert_allclose(effort, kp * (target - q) - kd * qd, rtol=1e-12, atol=1e-9)
    engine.set_joint_targets(names, "velocity", np.ones(n), kp, kd, np.full(n, 5.0))
    engine.step(1)
    _, qd, effort = engine.get_joint_states(names)
    np.testing.assert_allclose(effort, np.clip(kd * 1.0, -5, 5) - kd * qd, rtol=1e-12)
    engine.set_joint_targets(names, "effort", np.full(n, -7.0), kp, kd, np.full(n, 5.0))
    engine.step(1)
    np.testing.assert_array_equal(engine.get_joint_states(names)[2], -5.0)
    assert {j.mode for j in engine.joints()} == {"effort"}
    engine.set_joint_targets(names, "none", np.zeros(n), kp, kd, np.full(n, np.inf))
    engine.step(1)
    np.testing.assert_array_equal(engine.get_joint_states(names)[2], 0.0)


def test_a_position_target_is_reached_and_held(engine: MujocoEngine) -> None:
    """Within 0.02 rad (kp = 2000 N·m/rad against kuka's gravity torques, up to 33 N·m)
    after 3 s, still to 1e-4 rad over the next second."""
    names = kuka(engine)
    n = len(names)
    target = np.array([0.3, -0.4, 0.2, 0.8, -0.3, 0.5, 0.1])
    engine.set_joint_targets(names, "position", target, np.full(n, 2000.0),
                             np.full(n, 100.0), np.full(n, np.inf))
    engine.step(1500)
    reached = engine.get_joint_states(names)[0]
    np.testing.assert_allclose(reached, target, atol=0.02)
    engine.step(500)
    np.testing.assert_allclose(engine.get_joint_states(names)[0], reached, atol=1e-4)


def test_kuka_tracks_a_sine_within_0_04_rad(engine: MujocoEngine) -> None:
    """q_ref = 0.3 sin(pi t) on every joint, the target renewed every step, kp 5000,
    kd 150: after 0.5 s every joint within 0.04 rad of the reference (measured 0.03)."""
    names = kuka(engine)
    n, dt = len(names), engine.timestep
    worst = 0.0
    for k in range(1500):
        reference = np.full(n, 0.3 * math.sin(math.pi * k * dt))
        engine.set_joint_targets(names, "position", reference, np.full(n, 5000.0),
                                 np.full(n, 150.0), np.full(n, 300.0))
        engine.step(1)
        if k * dt > 0.5:
            now = 0.3 * math.sin(math.pi * (k + 1) * dt)
            worst = max(worst, float(np.abs(engine.get_joint_states(names)[0] - now).max()))
    assert worst < 0.04


def test_a_horizontal_link_held_by_a_target_needs_m_g_d(engine: MujocoEngine) -> None:
    engine.load_model("mjcf", HORIZONTAL, None, "h/")
    mass, distance, _ = about_the_hinge(engine, "h/bob")
    engine.set_joint_targets(["h/swing"], "position", ZERO, np.full(1, 5000.0),
                             np.full(1, 50.0), INF)
    engine.step(2000)
    q, qd, effort = engine.get_joint_states(["h/swing"])
    # +y hinge: gravity turns a bob on +x towards positive angles; the target pushes back
    assert -effort[0] == pytest.approx(mass * GRAVITY * distance, rel=0.01)
    assert abs(q[0]) < 0.01 and abs(qd[0]) < 1e-6


@pytest.mark.parametrize(("model", "joint", "push", "slack"), [
    ("cartpole.urdf", "m/slider_to_cart", 100.0, 1e-3),
    (KUKA, "m/lbr_iiwa_joint_1", 50.0, 2e-3)])
def test_joint_limits_hold_under_a_driving_effort(engine: MujocoEngine, model: str, joint: str,
                                                  push: float, slack: float) -> None:
    """MuJoCo's limits are soft: measured past them by 0.16 mm and 0.9 mrad."""
    engine.set_params({"mujoco.integrator": "implicitfast"})
    engine.load_model("urdf", urdf_text(model), None, "m/")
    upper = next(j.upper for j in engine.joints() if j.name == joint)
    assert upper is not None
    engine.set_joint_states([joint], np.full(1, upper - 0.1), None)
    engine.set_joint_targets([joint], "effort", np.full(1, push), ZERO, ZERO, INF)
    engine.step(2000)
    assert upper < engine.get_joint_states([joint])[0][0] < upper + slack


def run_with_teleports(engine: MujocoEngine) -> np.ndarray:
    names = kuka(engine)
    engine.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["ball"],
                            poses=np.array([[0.5, 0, 2, 0, 0, 0, 1.0]]))])
    engine.set_joint_targets(names[:3], "velocity", np.ones(3), np.ones(3), np.full(3, 5.0),
                             np.full(3, 50.0))
    engine.step(100)
    engine.set_joint_states(names[3:], np.full(4, 0.4), np.full(4, -0.2))
    engine.set_wrenches(["k/lbr_iiwa_link_7"], np.array([[0, 0, 5.0, 0, 0, 1.0]]), None)
    engine.step(100)
    return np.concatenate([*engine.get_joint_states(names), *engine.get_states(["ball"])],
                          axis=None)


def test_teleports_targets_and_wrenches_replay_bit_identically() -> None:
    np.testing.assert_array_equal(run_with_teleports(MujocoEngine()),
                                  run_with_teleports(MujocoEngine()))


def test_targets_survive_a_recompile(engine: MujocoEngine) -> None:
    names = kuka(engine)
    engine.set_joint_targets(names[:1], "effort", np.full(1, 3.0), ONE, ONE, INF)
    engine.spawn([BodyGroup(shape="box", size=(0.1, 0.1, 0.1), names=["c"], mass=3.0,
                            poses=np.array([[2, 0, 1, 0, 0, 0, 1.0]]))])
    engine.step(1)
    np.testing.assert_array_equal(engine.get_joint_states(names)[2], [3.0, 0, 0, 0, 0, 0, 0])


def test_restore_joints_puts_back_positions_modes_and_wrenches(engine: MujocoEngine) -> None:
    names = kuka(engine)
    engine.set_joint_targets(names, "effort", np.full(7, 2.0), np.ones(7), np.ones(7),
                             np.full(7, np.inf))
    engine.set_wrenches(["k/lbr_iiwa_link_3"], np.ones((1, 6)), None)
    engine.step(200)
    engine.restore_joints()
    q, qd, effort = engine.get_joint_states(names)
    assert not q.any() and not qd.any() and not effort.any()
    assert {j.mode for j in engine.joints()} == {"none"}
    assert not engine.data.xfrc_applied.any()
    engine.step(10)
    assert not engine.get_joint_states(names)[2].any()


def test_a_model_with_joints_never_falls_asleep(engine: MujocoEngine) -> None:
    """Its actuators keep its tree awake, so a teleport or a target needs no waking."""
    names = kuka(engine)
    engine.set_joint_targets(names, "position", np.zeros(7), np.full(7, 100.0),
                             np.full(7, 10.0), np.full(7, np.inf))
    engine.step(3000)
    assert engine.data.ntree_awake == engine.model.ntree


def test_a_wrench_wakes_a_sleeping_body(engine: MujocoEngine) -> None:
    engine.spawn([BodyGroup(shape="plane", size=(5, 5), names=["ground"], static=True,
                            poses=np.array([[0, 0, 0, 0, 0, 0, 1.0]])),
                  BodyGroup(shape="sphere", size=(0.1,), names=["b"],
                            poses=np.array([[0, 0, 0.1, 0, 0, 0, 1.0]]))])
    engine.step(3000)
    assert engine.data.ntree_awake == 0
    engine.set_wrenches(["b"], np.array([[0, 0, 200.0, 0, 0, 0]]), None)  # 4.2 kg
    engine.step(50)
    assert engine.get_states(["b"])[0][0, 2] > 0.15  # 0.1 + 38 m/s² x (0.1 s)² / 2
