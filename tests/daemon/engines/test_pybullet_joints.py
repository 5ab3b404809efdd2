"""The PyBullet engine's articulated models, in-process: roots and links as entities, joints,
the actuator law, wrenches, and what a rebuild keeps; physics checked against theory."""

from __future__ import annotations

import math
import os
from collections.abc import Iterator

import numpy as np
import pybullet_data
import pytest

from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.protocol import BodyGroup, NameNotUniqueError, NotFoundError

DATA = pybullet_data.getDataPath()
GRAVITY = 9.81
MASS, ARM, SPIN = 1.0, 0.5, 1e-4  # the pendulum's bob: kg, m from the pivot, kg m² own
INF = np.inf


def pendulum(lower: float = -3.0, upper: float = 3.0, turn: str = "0 0 0") -> str:
    """A point-ish mass on a massless rod, hinged about x at 1 m; its inertial frame is
    offset (and turned by ``turn``) from its link frame, which sits at the pivot."""
    return f"""<robot name="pendulum">
  <link name="pivot"/>
  <link name="bob">
    <inertial><origin xyz="0 0 {-ARM}" rpy="{turn}"/><mass value="{MASS}"/>
      <inertia ixx="{SPIN}" iyy="{SPIN}" izz="{SPIN}" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="swing" type="revolute"><parent link="pivot"/><child link="bob"/>
    <origin xyz="0 0 1"/><axis xyz="1 0 0"/>
    <limit lower="{lower}" upper="{upper}" effort="50" velocity="20"/></joint>
</robot>"""


def model_text(relative: str) -> str:
    """A pybullet_data model with its mesh paths made absolute (model_files.py's job)."""
    folder = os.path.dirname(os.path.join(DATA, relative))
    with open(os.path.join(DATA, relative), encoding="utf-8") as handle:
        text = handle.read()
    return text.replace('filename="', f'filename="{folder}/')


@pytest.fixture
def engine() -> Iterator[PybulletEngine]:
    eng = PybulletEngine()
    yield eng
    eng.close()


def one(value: float) -> np.ndarray:
    return np.array([value])


def hold(engine: PybulletEngine, mode: str, target: float, kp: float = 0.0,
         kd: float = 0.0, max_effort: float = INF, joint: str = "p/swing") -> None:
    engine.set_joint_targets([joint], mode, one(target), one(kp), one(kd), one(max_effort))


def state(engine: PybulletEngine, joint: str = "p/swing") -> tuple[float, float, float]:
    q, qdot, effort = engine.get_joint_states([joint])
    return float(q[0]), float(qdot[0]), float(effort[0])


# -- models as entities ------------------------------------------------------------------
def test_kuka_loads_as_a_root_and_seven_links(engine: PybulletEngine) -> None:
    infos = engine.load_model("urdf", model_text("kuka_iiwa/model.urdf"), None, "k/")
    root = "k/lbr_iiwa_link_0"
    assert [(i.name, i.shape, i.model, i.static) for i in infos] == [
        (root, "model", root, True),
        *((f"k/lbr_iiwa_link_{j}", "link", root, False) for j in range(1, 8))]
    joints = engine.joints()
    assert [j.name for j in joints] == [f"k/lbr_iiwa_joint_{j}" for j in range(1, 8)]
    assert {(j.type, j.axis, j.mode, j.damping, j.effort_limit) for j in joints} == {
        ("revolute", (0.0, 0.0, 1.0), "none", 0.5, 300.0)}
    assert joints[0].parent == root and joints[6].child == "k/lbr_iiwa_link_7"
    assert joints[1].lower == pytest.approx(-2.0944, abs=1e-4) and joints[1].upper > 2.09
    engine.set_params({"timestep": 0.001})  # see test_kuka_tracks_a_sinusoid
    engine.step(1000)  # no default motor holds the joints: the arm sags (joint 2 is loaded)
    assert np.ptp(engine.get_joint_states([j.name for j in joints])[0]) > 1e-3


def test_r2d2_floating_lists_every_joint_type(engine: PybulletEngine) -> None:
    infos = engine.load_model("urdf", model_text("r2d2.urdf"), None, "", fixed_base=False)
    assert infos[0].name == "base_link" and not infos[0].static and len(infos) == 16
    joints = {j.name: j for j in engine.joints()}
    assert (joints["base_link:free"].type, joints["base_link:free"].parent) == ("free", "")
    assert joints["base_to_right_leg"].type == "fixed"
    wheel = joints["right_front_wheel_joint"]  # continuous: revolute without limits
    assert (wheel.type, wheel.lower, wheel.upper) == ("revolute", None, None)
    head = joints["head_swivel"]  # continuous, with a <limit> PyBullet reports
    assert (head.type, head.lower, head.upper) == ("revolute", None, None)
    grip = joints["gripper_extension"]
    assert (grip.type, grip.lower, grip.upper, grip.axis) == ("prismatic", -0.38, 0.0,
                                                              (1.0, 0.0, 0.0))


def test_the_axis_is_in_the_child_link_frame(engine: PybulletEngine) -> None:
    """PyBullet gives it in the child's inertial frame; this one is turned 90° about y."""
    engine.load_model("urdf", pendulum(turn="0 1.5707963267948966 0"), None, "p/")
    np.testing.assert_allclose(engine.joints()[0].axis, (1, 0, 0), atol=1e-7)


def test_a_link_pose_is_its_frame_and_its_twist_the_frame_origin(
        engine: PybulletEngine) -> None:
    engine.load_model("urdf", pendulum(), None, "p/")
    engine.set_joint_states(["p/swing"], one(0.3), one(2.0))
    poses, twists = engine.get_states(["p/bob", "p/pivot"])
    # PyBullet's link frames are computed in single precision: 1.5e-8 m off, at 1 m.
    np.testing.assert_allclose(poses[0], [0, 0, 1, math.sin(0.15), 0, 0, math.cos(0.15)],
                               atol=1e-7)
    np.testing.assert_allclose(twists[0], [0, 0, 0, 2.0, 0, 0], atol=1e-7)  # on the axis
    np.testing.assert_allclose(poses[1], [0, 0, 0, 0, 0, 0, 1], atol=1e-7)
    assert engine.properties(["p/bob"])[0, 0] == MASS


def test_a_floating_root_reads_and_sets_its_link_frame(engine: PybulletEngine) -> None:
    """The root's centre of mass is 0.1 m above its frame: get_states and set_states
    speak of the frame, and of its origin's velocity."""
    text = pendulum().replace('<link name="pivot"/>', """<link name="pivot"><inertial>
      <origin xyz="0 0 0.1"/><mass value="2"/>
      <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>""")
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    engine.load_model("urdf", text, None, "p/", fixed_base=False)
    turned = np.array([[1.0, 2.0, 3.0, 0.0, math.sin(0.5), 0.0, math.cos(0.5)]])
    twist = np.array([[0.0, 0.0, 0.0, 0.0, 0.0, 4.0]])
    engine.set_states(["p/pivot"], turned, twist)
    poses, twists = engine.get_states(["p/pivot"])
    np.testing.assert_allclose(poses, turned, atol=1e-12)
    np.testing.assert_allclose(twists, twist, atol=1e-12)
    engine.reset_dynamics()  # a rebuild sets the pose as given again
    np.testing.assert_array_equal(engine.get_states(["p/pivot"])[0], poses)


def test_mjcf_lists_the_files_bodies_and_joints(engine: PybulletEngine) -> None:
    """Not the links and welds PyBullet's importer adds; the world's geoms are a model
    (named by PyBullet), and so is the cart's anchor (PyBullet's base, under its name)."""
    with open(os.path.join(DATA, "mjcf/inverted_pendulum.xml"), encoding="utf-8") as handle:
        infos = engine.load_model("mjcf", handle.read(), None, "ip/")
    assert [(i.name, i.shape, i.model) for i in infos] == [
        ("ip/rail", "model", "ip/rail"), ("ip/link1_1", "model", "ip/link1_1"),
        ("ip/cart", "link", "ip/link1_1"), ("ip/pole", "link", "ip/link1_1")]
    assert [(j.name, j.type, j.parent, j.child, j.axis) for j in engine.joints()] == [
        ("ip/slider", "prismatic", "ip/link1_1", "ip/cart", (1.0, 0.0, 0.0)),
        ("ip/hinge", "revolute", "ip/cart", "ip/pole", (0.0, 1.0, 0.0))]
    assert engine.get_states(["ip/pole"])[0].shape == (1, 7)


def test_an_mjcf_free_joint_keeps_its_name(engine: PybulletEngine) -> None:
    text = """<mujoco><worldbody><body name="ball" pos="0 0 1"><freejoint name="loose"/>
      <geom type="sphere" size="0.1"/></body></worldbody></mujoco>"""
    [info] = engine.load_model("mjcf", text, None, "m/")
    assert (info.name, info.static) == ("m/ball", False)
    assert [(j.name, j.type, j.parent, j.child) for j in engine.joints()] == [
        ("m/loose", "free", "", "m/ball")]


def test_mjcf_inertia_is_the_files(engine: PybulletEngine) -> None:
    """PyBullet's importer takes it from the geoms; the engine sets the file's again."""
    text = """<mujoco><worldbody><body name="base" pos="0 0 2"><body name="bob">
      <joint name="hinge" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 -0.5" mass="1" diaginertia="0.01 0.02 0.03"/>
      <geom type="sphere" size="0.02" pos="0 0 -0.5" mass="0"/></body></body>
      </worldbody></mujoco>"""
    engine.load_model("mjcf", text, None, "p/")
    root, link = engine.robots.links["p/bob"]
    info = engine._bc.getDynamicsInfo(engine.bodies[root].uid, link)
    assert (info[0], info[2]) == (1.0, (0.01, 0.02, 0.03))


def test_names_in_use_are_refused_and_leave_nothing(engine: PybulletEngine) -> None:
    engine.spawn([BodyGroup("sphere", (0.1,), ["p/bob"], np.array([[5.0, 0, 1, 0, 0, 0, 1]]))])
    with pytest.raises(NameNotUniqueError, match="p/bob"):
        engine.load_model("urdf", pendulum(), None, "p/")
    assert list(engine.bodies) == ["p/bob"] and engine.joints() == []
    engine.load_model("urdf", pendulum(), None, "q/")
    with pytest.raises(NameNotUniqueError, match="q/swing"):
        engine.load_model("urdf", pendulum().replace('"pivot"', '"hub"').replace(
            '"bob"', '"mass"'), None, "q/")


def test_unknown_joints_and_bodies_are_not_found(engine: PybulletEngine) -> None:
    engine.load_model("urdf", pendulum(), None, "p/")
    with pytest.raises(NotFoundError, match="p/swing"):
        engine.get_joint_states(["p/swung"])
    with pytest.raises(NotFoundError):
        engine.set_wrenches(["nobody"], np.zeros((1, 6)), None)


def test_delete_and_clear_take_links_joints_targets_and_wrenches(
        engine: PybulletEngine) -> None:
    engine.load_model("urdf", pendulum(), None, "p/")
    hold(engine, "effort", 1.0)
    engine.set_wrenches(["p/bob"], np.ones((1, 6)), None)
    engine.delete(["p/pivot"])
    assert engine.joints() == [] and not engine.robots.wrenches and not engine.robots.links
    engine.load_model("urdf", pendulum(), None, "p/")
    engine.clear()
    assert engine.joints() == [] and not engine.robots.links


# -- the actuator law --------------------------------------------------------------------
def test_the_law_is_applied_exactly_and_clipped(engine: PybulletEngine) -> None:
    """The stiffness at the step's start, the damping at the velocity it ends with
    (pybullet_joints' docstring: "stable PD" on a fixed base)."""
    engine.load_model("urdf", pendulum(), None, "p/")
    engine.set_joint_states(["p/swing"], one(0.2), one(-0.7))
    hold(engine, "position", 0.5, kp=30.0, kd=2.0)
    engine.step(1)
    _, qdot, effort = state(engine)
    assert effort == pytest.approx(30.0 * (0.5 - 0.2) - 2.0 * qdot, rel=1e-9)
    hold(engine, "velocity", 1.5, kd=3.0)
    engine.step(1)
    _, qdot, effort = state(engine)
    assert effort == pytest.approx(3.0 * (1.5 - qdot), rel=1e-9)
    hold(engine, "effort", 10.0, max_effort=2.0)
    engine.step(1)
    assert state(engine)[2] == 2.0
    assert engine.joints()[0].mode == "effort"
    hold(engine, "none", 0.0)
    engine.step(1)
    assert state(engine)[2] == 0.0 and engine.joints()[0].mode == "none"


def test_a_velocity_target_is_reached(engine: PybulletEngine) -> None:
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    engine.load_model("urdf", pendulum(lower=1.0, upper=-1.0), None, "p/")  # unlimited
    hold(engine, "velocity", 1.0, kd=5.0)
    engine.step(480)
    assert state(engine)[1] == pytest.approx(1.0, abs=1e-9)


def test_a_position_target_is_reached_and_held(engine: PybulletEngine) -> None:
    """Within 1e-3 rad, the spring's static error m g d sin(q) / kp = 4.7e-4 rad being
    most of it; then it does not move."""
    engine.load_model("urdf", pendulum(), None, "p/")
    inertia = SPIN + MASS * ARM**2
    kp = 5000.0
    hold(engine, "position", 0.5, kp=kp, kd=2 * math.sqrt(kp * inertia))
    engine.step(720)
    q, qdot, _ = state(engine)
    assert abs(q - 0.5) < 1e-3 and abs(qdot) < 1e-6
    engine.step(240)
    assert abs(state(engine)[0] - q) < 1e-9


def test_holding_a_horizontal_link_takes_m_g_d(engine: PybulletEngine) -> None:
    engine.load_model("urdf", pendulum(), None, "p/")
    inertia = SPIN + MASS * ARM**2
    hold(engine, "position", math.pi / 2, kp=2000.0, kd=2 * math.sqrt(2000.0 * inertia))
    engine.step(960)
    assert abs(state(engine)[2]) == pytest.approx(MASS * GRAVITY * ARM, rel=0.01)


def test_a_limit_holds_against_a_driving_effort(engine: PybulletEngine) -> None:
    """Bullet's limit is a constraint: it gives a little under 20 N·m, within 0.01 rad."""
    engine.load_model("urdf", pendulum(lower=-0.5, upper=0.5), None, "p/")
    hold(engine, "effort", 20.0)
    engine.step(480)
    q, qdot, effort = state(engine)
    assert abs(q - 0.5) < 0.01 and abs(qdot) < 0.01 and effort == 20.0


# -- physics against theory --------------------------------------------------------------
def test_a_pendulum_swings_with_its_small_angle_period(engine: PybulletEngine) -> None:
    """T = 2 pi sqrt(I / (m g d)), I about the pivot, within 1 % (released at 0.05 rad)."""
    engine.load_model("urdf", pendulum(), None, "p/")
    engine.set_joint_states(["p/swing"], one(0.05), one(0.0))
    dt, angles = engine.timestep, []
    for _ in range(1200):
        engine.step(1)
        angles.append(state(engine)[0])
    a = np.array(angles)
    k = np.nonzero((a[:-1] > 0) & (a[1:] <= 0))[0]
    crossings = (k + a[k] / (a[k] - a[k + 1])) * dt
    period = float(np.mean(np.diff(crossings)))
    theory = 2 * math.pi * math.sqrt((SPIN + MASS * ARM**2) / (MASS * GRAVITY * ARM))
    assert len(crossings) >= 3 and period == pytest.approx(theory, rel=0.01)


@pytest.mark.parametrize("target", ["ball", "p/pivot"])
def test_a_wrench_gives_f_over_m(engine: PybulletEngine, target: str) -> None:
    """On a spawned ball and a floating model's root (the whole model moves: m = 3 kg);
    no gravity, 1 s."""
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    engine.spawn([BodyGroup("sphere", (0.1,), ["ball"], np.array([[5.0, 0, 1, 0, 0, 0, 1]]),
                            mass=2.0)])
    text = pendulum().replace('<link name="pivot"/>', """<link name="pivot"><inertial>
      <mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
      </inertial></link>""")
    engine.load_model("urdf", text, None, "p/", fixed_base=False)
    mass = 2.0 if target == "ball" else 3.0
    force = np.array([[3.0, -1.0, 0.5, 0.0, 0.0, 0.0]])
    before = engine.get_states(["ball", "p/pivot"])[1]
    engine.set_wrenches([target], force, None)
    steps = round(1 / engine.timestep)
    engine.step(steps)
    row = 0 if target == "ball" else 1
    if target == "ball":
        velocity = engine.get_states(["ball"])[1][0, :3] - before[row, :3]
    else:  # the model's centre of mass: its momentum over its mass
        velocity = momentum(engine) / mass
    np.testing.assert_allclose(velocity, force[0, :3] / mass * steps * engine.timestep,
                               rtol=0.01, atol=1e-9)


def momentum(engine: PybulletEngine) -> np.ndarray:
    """The floating pendulum's linear momentum, from its base's and bob's centres."""
    bc, uid = engine._bc, engine.bodies["p/pivot"].uid
    base = np.array(bc.getBaseVelocity(uid)[0]) * 2.0
    bob = np.array(bc.getLinkState(uid, 0, computeLinkVelocity=1,
                                   computeForwardKinematics=1)[6]) * MASS
    return base + bob


def test_a_wrench_on_a_link_turns_its_joint(engine: PybulletEngine) -> None:
    """1 N across the bob, 0.5 m below the hinge: qddot = 0.5 N·m / I for 0.1 s (the
    bob turns 0.02 rad: the world-fixed force stays across it within 2e-4)."""
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    engine.load_model("urdf", pendulum(), None, "p/")
    engine.set_wrenches(["p/bob"], np.array([[0.0, 1.0, 0, 0, 0, 0]]), None)
    steps = 24
    engine.step(steps)
    inertia = SPIN + MASS * ARM**2
    assert state(engine)[1] == pytest.approx(ARM / inertia * steps * engine.timestep, rel=0.01)


def test_a_wrench_at_a_point_turns_a_ball(engine: PybulletEngine) -> None:
    """F at p = r above the centre: a = F/m and alpha = r x F / I, I = 2/5 m r²."""
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    radius, mass = 0.1, 2.0
    engine.spawn([BodyGroup("sphere", (radius,), ["ball"], np.array([[0.0, 0, 1, 0, 0, 0, 1]]),
                            mass=mass)])
    engine.set_wrenches(["ball"], np.array([[1.0, 0, 0, 0, 0, 0]]), np.array([[0, 0, 1.1]]))
    engine.step(24)
    _, twists = engine.get_states(["ball"])
    t = 24 * engine.timestep
    inertia = 0.4 * mass * radius**2
    np.testing.assert_allclose(twists[0], [t / mass, 0, 0, 0, radius * t / inertia, 0],
                               rtol=0.01, atol=1e-9)
    engine.clear_wrenches(None)
    engine.step(24)
    np.testing.assert_allclose(engine.get_states(["ball"])[1], twists, rtol=1e-9)


def test_kuka_tracks_a_sinusoid(engine: PybulletEngine) -> None:
    """Position targets q_d = 0.3 sin(2 pi 0.5 t) on every joint, gains from the mass
    matrix's diagonal (natural frequency 80 rad/s, critically damped; kp at least 300
    N·m/rad against joint 7's own damping): after a 0.5 s transient every joint stays
    within 0.03 rad of its target (a PD's lag, 2 A w / w_n = 0.024 rad, is most of it).

    At 1 ms steps: Bullet applies the file's joint damping explicitly, and joint 7's (0.5
    N·m·s/rad on 0.001 kg·m²) is unstable beyond 2 ms (c dt / I > 2; at the default 1/240
    s the free arm's last joint spins up to Bullet's 100 rad/s clamp)."""
    engine.set_params({"timestep": 0.001})
    engine.load_model("urdf", model_text("kuka_iiwa/model.urdf"), None, "k/")
    names = [j.name for j in engine.joints()]
    uid = engine.bodies["k/lbr_iiwa_link_0"].uid
    inertia = np.diag(engine._bc.calculateMassMatrix(uid, [0.0] * 7))
    omega, dt = 80.0, engine.timestep
    kp, kd = np.maximum(omega**2 * inertia, 300.0), 2 * omega * inertia
    worst = 0.0
    for k in range(1, 2001):
        wanted = np.full(7, 0.3 * math.sin(math.pi * k * dt))
        engine.set_joint_targets(names, "position", wanted, kp, kd, np.full(7, INF))
        engine.step(1)
        if k * dt > 0.5:
            worst = max(worst, float(np.abs(engine.get_joint_states(names)[0] - wanted).max()))
    assert worst < 0.03


# -- what a rebuild keeps ----------------------------------------------------------------
def test_a_rebuild_keeps_targets_wrenches_and_joint_states(engine: PybulletEngine) -> None:
    engine.load_model("urdf", pendulum(), None, "p/", fixed_base=False)
    hold(engine, "position", 0.4, kp=100.0, kd=5.0)
    engine.set_wrenches(["p/bob"], np.array([[0.0, 0, 5.0, 0, 0, 0]]), None)
    engine.step(100)
    before = state(engine)
    engine.reset_dynamics()
    assert state(engine)[:2] == before[:2] and engine.joints()[1].mode == "position"
    assert "p/bob" in engine.robots.wrenches
    engine.step(100)
    other = PybulletEngine()  # the same run without the rebuild
    try:
        other.load_model("urdf", pendulum(), None, "p/", fixed_base=False)
        hold(other, "position", 0.4, kp=100.0, kd=5.0)
        other.set_wrenches(["p/bob"], np.array([[0.0, 0, 5.0, 0, 0, 0]]), None)
        other.step(200)
        assert state(engine) == pytest.approx(state(other), rel=1e-9, abs=1e-12)
    finally:
        other.close()


def test_a_rewound_model_with_targets_replays_bit_for_bit(engine: PybulletEngine) -> None:
    engine.spawn([BodyGroup("plane", (5.0, 5.0), ["ground"], np.array([[0.0, 0, 0, 0, 0, 0, 1]]),
                            static=True)])
    engine.load_model("urdf", model_text("kuka_iiwa/model.urdf"), None, "k/")
    names = [j.name for j in engine.joints()]
    root = "k/lbr_iiwa_link_0"
    pose, twist = engine.get_states([root])

    def run() -> np.ndarray:
        engine.set_joint_targets(names, "position", np.full(7, 0.4), np.full(7, 50.0),
                                 np.full(7, 1.0), np.full(7, 100.0))
        engine.set_wrenches(["k/lbr_iiwa_link_7"], np.array([[0, 0, 10.0, 0, 0, 0]]), None)
        engine.step(300)
        out = np.hstack([*engine.get_joint_states(names),
                         *engine.get_states(["k/lbr_iiwa_link_7"])[0]])
        engine.set_states([root], pose, twist)
        engine.restore_joints()
        engine.reset_dynamics()
        return out

    first, again = run(), run()
    np.testing.assert_array_equal(first, again)
    assert engine.joints()[0].mode == "none" and not engine.robots.wrenches


def test_a_hundred_joint_chain_on_one_line_loads(engine: PybulletEngine) -> None:
    """PyBullet's XML reader fails on lines past about 16 kB: the engine breaks them."""
    inertial = ('<inertial><origin xyz="0 0 0.05"/><mass value="0.1"/><inertia ixx="0.0001" '
                'iyy="0.0001" izz="0.0001" ixy="0" ixz="0" iyz="0"/></inertial>')
    links = "".join(f'<link name="l{i}">{inertial}</link>' for i in range(101))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="1 0 0"/>'
        '<limit lower="-1" upper="1" effort="10" velocity="10"/></joint>' for i in range(100))
    engine.load_model("urdf", f'<robot name="chain">{links}{joints}</robot>', None, "c/")
    names = [f"c/j{i}" for i in range(100)]
    assert [j.name for j in engine.joints()] == names
    assert engine.get_joint_states(names)[0].shape == (100,)
