"""The PyBullet engine on its own, in-process: bodies, states, physics, parameters, models.

What every engine must do is checked by galton.daemon.engines.check (test_engine_check.py);
here is what is PyBullet's own: its calls, its tuning, its rebuilds and its memory.
"""

from __future__ import annotations

import gc
import math
import os
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from support.materials import board_defaults
from support.urdf import ARM_URDF

from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
)

GRAVITY = 9.81
PAGE_BYTES = os.sysconf("SC_PAGE_SIZE")
RADIUS = 0.05
TINY_URDF = """<robot name="crate_bot">
  <link name="crate">
    <inertial><mass value="2"/>
      <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
  </link>
</robot>"""
TINY_MJCF = """<mujoco model="pair">
  <worldbody>
    <geom type="plane" size="5 5 0.1"/>
    <body name="ball" pos="0 0 1"><joint type="free"/><geom type="sphere" size="0.1"/></body>
    <body name="ball" pos="1 0 1"><joint type="free"/><geom type="sphere" size="0.1"/></body>
  </worldbody>
</mujoco>"""


@pytest.fixture
def engine() -> Iterator[PybulletEngine]:
    eng = PybulletEngine()
    yield eng
    eng.close()


def poses_at(positions: Any) -> np.ndarray:
    positions = np.atleast_2d(np.asarray(positions, dtype=float))
    out = np.zeros((len(positions), 7))
    out[:, :3] = positions
    out[:, 6] = 1.0
    return out


def balls(names: list[str], positions: Any, **options: Any) -> BodyGroup:
    return BodyGroup("sphere", (RADIUS,), names, poses_at(positions), **options)


def ground() -> BodyGroup:
    return BodyGroup("plane", (5.0, 5.0), ["ground"], poses_at([0, 0, 0]), static=True)


def grid(count: int, spacing: float = 0.11, z: float = 0.5) -> np.ndarray:
    i = np.arange(count)
    return np.column_stack([i % 10 * spacing, i // 10 % 10 * spacing, z + i // 100 * spacing])


def body_id(engine: PybulletEngine, name: str) -> int:
    return engine.bodies[name].uid


# -- description and parameters ----------------------------------------------------------
def test_capabilities_name_every_shape_format_and_parameter(engine: PybulletEngine) -> None:
    caps = engine.capabilities()
    assert caps.engine == "pybullet" and caps.engine_version.startswith("3.")
    assert set(caps.body_shapes) == {"sphere", "box", "cylinder", "capsule", "plane", "mesh"}
    assert caps.model_formats == ("urdf", "mjcf")
    assert set(caps.params) == set(engine.get_params())
    assert {"timestep", "gravity", "solver_iterations", "default_friction",
            "default_restitution"} <= set(caps.params)
    assert caps.params["gravity"]["default"] == [0.0, 0.0, -9.81]


def test_params_apply_and_keep_the_world(engine: PybulletEngine) -> None:
    engine.spawn([balls(["a"], [0, 0, 1])])
    engine.step(10)
    before = engine.get_states(["a"])
    engine.set_params({"timestep": 0.002, "solver_iterations": 12, "gravity": [0, 0, -1.62],
                       "pybullet.enable_cone_friction": False})
    after = engine.get_states(["a"])
    assert all(np.array_equal(x, y) for x, y in zip(before, after, strict=True))
    world = engine._bc.getPhysicsEngineParameters()
    assert world["fixedTimeStep"] == 0.002 and world["numSolverIterations"] == 12
    assert world["gravityAccelerationZ"] == pytest.approx(-1.62)
    assert engine.timestep == 0.002
    assert engine.get_params()["gravity"] == [0.0, 0.0, -1.62]


def test_params_are_all_or_none(engine: PybulletEngine) -> None:
    with pytest.raises(InvalidArgumentError, match="solver_iterations"):
        engine.set_params({"timestep": 0.01, "solver_iterations": 0})
    assert engine.get_params()["timestep"] == pytest.approx(1 / 240)
    assert engine._bc.getPhysicsEngineParameters()["fixedTimeStep"] == pytest.approx(1 / 240)


def test_cone_friction_takes_only_a_boolean(engine: PybulletEngine) -> None:
    with pytest.raises(InvalidArgumentError, match="enable_cone_friction"):
        engine.set_params({"pybullet.enable_cone_friction": 1})


def test_default_friction_follows_bodies_that_set_none(engine: PybulletEngine) -> None:
    engine.spawn([balls(["plain"], [0, 0, 1]), balls(["own"], [1, 0, 1], friction=0.9)])
    engine.set_params({"default_friction": 0.2})
    friction = {n: engine._bc.getDynamicsInfo(body_id(engine, n), -1)[1] for n in ("plain", "own")}
    assert friction == {"plain": pytest.approx(0.2), "own": pytest.approx(0.9)}


def test_collision_margin_reaches_shared_box_shapes(engine: PybulletEngine) -> None:
    boxes = BodyGroup("box", (0.1, 0.1, 0.1), ["b0", "b1"], poses_at([[0, 0, 1], [1, 0, 1]]))
    engine.spawn([boxes])
    engine.set_params({"pybullet.collision_margin": 0.02})
    margins = [engine._bc.getDynamicsInfo(body_id(engine, n), -1)[11] for n in ("b0", "b1")]
    assert margins == [pytest.approx(0.02)] * 2
    engine.spawn([BodyGroup("box", (0.1, 0.1, 0.1), ["b2"], poses_at([2, 0, 1]))])
    assert engine._bc.getDynamicsInfo(body_id(engine, "b2"), -1)[11] == pytest.approx(0.02)


# -- bodies and states -------------------------------------------------------------------
def test_a_pose_alone_keeps_the_twist_and_a_twist_alone_the_pose(
        engine: PybulletEngine) -> None:
    """resetBasePositionAndOrientation zeroes a body's twist; the engine sets it again."""
    engine.spawn([balls(["a"], [0, 0, 1], twists=np.array([[1.0, 0, 2, 0, 3, 0]]))])
    arm, _ = engine.load_model("urdf", ARM_URDF, None, "m/", fixed_base=False)
    names = ["a", arm.name]
    engine.set_states([arm.name], None, np.array([[0.5, 0, 0, 0, 0, 0.2]]))
    _, twists = engine.get_states(names)
    moved = poses_at([[1, 1, 2], [2, 2, 2]])
    moved[1, 3:] = [0, 0, math.sin(0.2), math.cos(0.2)]
    engine.set_states(names, moved, None)
    poses, kept = engine.get_states(names)
    np.testing.assert_array_equal(kept, twists)
    np.testing.assert_allclose(poses, moved, atol=1e-15)
    engine.set_states(names, None, np.zeros((2, 6)))
    np.testing.assert_array_equal(engine.get_states(names)[0], poses)


def test_default_mass_is_water_density_and_capsule_inertia_is_exact(
        engine: PybulletEngine) -> None:
    engine.spawn([BodyGroup("box", (0.1, 0.2, 0.3), ["box"], poses_at([0, 0, 1])),
                  BodyGroup("capsule", (0.1, 0.2), ["cap"], poses_at([1, 0, 1]))])
    mass, _, inertia = engine._bc.getDynamicsInfo(body_id(engine, "box"), -1)[:3]
    assert mass == pytest.approx(1000 * 0.2 * 0.4 * 0.6)
    mass, _, inertia = engine._bc.getDynamicsInfo(body_id(engine, "cap"), -1)[:3]
    assert mass == pytest.approx(1000 * (math.pi * 0.01 * 0.4 + 4 / 3 * math.pi * 0.001))
    assert inertia[2] < inertia[0]  # slender along z; Bullet's own box estimate is 5x off


def test_a_thousand_bodies_come_from_one_create_call(
        engine: PybulletEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = []
    create = engine._bc.createMultiBody

    def counting(*args: Any, **kwargs: Any) -> Any:
        calls.append(len(kwargs.get("batchPositions", [None])))
        return create(*args, **kwargs)

    monkeypatch.setattr(engine._bc, "createMultiBody", counting)
    names = [f"b{i}" for i in range(1000)]
    engine.spawn([balls(names, grid(1000))])
    assert calls == [1000]
    poses, _ = engine.get_states(names)
    assert np.array_equal(poses[:, :3], grid(1000))


def test_spawning_after_deletes_finds_each_body(engine: PybulletEngine) -> None:
    """PyBullet reuses removed bodies' ids, and its batch call then misreports the ids."""
    engine.spawn([ground(), balls([f"a{i}" for i in range(20)], grid(20))])
    engine.delete(["a3", "a4", "a11"])
    engine._bc.removeBody(engine.bodies.pop("a7").uid)  # a hole the engine did not make
    names = [f"b{i}" for i in range(30)]
    engine.spawn([balls(names, grid(30, z=3.0))])
    assert np.array_equal(engine.get_states(names)[0][:, :3], grid(30, z=3.0))
    uids = [b.uid for b in engine.bodies.values()]
    assert len(set(uids)) == len(uids) == 1 + 16 + 30


def test_update_changes_dynamics_and_colour(engine: PybulletEngine) -> None:
    engine.spawn([ground(), balls(["a", "b"], [[0, 0, 1], [1, 0, 1]])])
    engine.update(["a"], BodyProperties(mass=2.0, friction=0.7, restitution=0.4,
                                        rgba=(0, 1, 0, 1)))
    uid = body_id(engine, "a")
    mass, friction, inertia = engine._bc.getDynamicsInfo(uid, -1)[:3]
    assert (mass, friction) == pytest.approx((2.0, 0.7))
    assert inertia == pytest.approx([0.4 * 2.0 * RADIUS**2] * 3)
    assert engine._bc.getVisualShapeData(uid)[0][7] == pytest.approx((0, 1, 0, 1))
    with pytest.raises(InvalidArgumentError, match="static"):
        engine.update(["ground"], BodyProperties(mass=1.0))


def test_restitution_makes_a_ball_bounce(engine: PybulletEngine) -> None:
    """Read back by its effect: getDynamicsInfo reports 0 for every rigid body."""
    engine.spawn([ground(), balls(["a"], [0, 0, 1.0 + RADIUS])])
    engine.update(["a", "ground"], BodyProperties(restitution=0.9))
    rising = []
    for _ in range(150):  # the ball lands after 0.45 s
        engine.step(1)
        rising.append(engine.get_states(["a"])[1][0, 2])
    impact = math.sqrt(2 * GRAVITY * 1.0)
    assert max(rising) / impact == pytest.approx(0.9 * 0.9, abs=0.1)  # the product, roughly


def drop_bounce(engine: PybulletEngine, height: float) -> float:
    """Coefficient of restitution of a ball dropped from rest ``height`` above a plane:
    the square root of the rebound height over the drop height."""
    engine.clear()
    engine.spawn([ground(), balls(["a"], [0, 0, RADIUS + height])])
    rebound, rising = 0.0, False
    for _ in range(int(2.2 * math.sqrt(2 * height / GRAVITY) / engine.timestep) + 24):
        engine.step(1)
        poses, twists = engine.get_states(["a"])
        rising = rising or twists[0, 2] > 0
        if rising:
            rebound = max(rebound, poses[0, 2] - RADIUS)
    return math.sqrt(rebound / height)


def mean_bounce(engine: PybulletEngine, height: float) -> float:
    """Mean of 8 drops from about ``height``: one drop alone varies by +-0.05 with where the
    impact falls within a step."""
    return float(np.mean([drop_bounce(engine, height * (1 + k / 97)) for k in range(8)]))


@pytest.mark.parametrize("height", [0.05, 0.5, 2.5])
def test_board_bounce_is_a_hard_ball_on_a_hard_floor(engine: PybulletEngine,
                                                     height: float) -> None:
    """The board's restitution 0.8275 on both bodies (0.8275² = 0.685): e about 0.70-0.72 at
    1, 3 and 7 m/s (docs/physics/pybullet.md)."""
    engine.set_params(board_defaults("pybullet"))
    assert mean_bounce(engine, height) == pytest.approx(0.71, abs=0.04)


def test_early_contacts_take_the_bounce_of_slow_balls(engine: PybulletEngine) -> None:
    """At a small step, a slow ball loses its bounce in contacts made before it touches
    (Bullet's 0.02 m); the board's 0.01 m keeps most of it, 0.001 m all of it."""
    engine.set_params(board_defaults("pybullet"))
    bounces = {}
    for gap in (0.02, 0.01, 0.001):
        engine.set_params({"timestep": 1 / 480, "pybullet.contact_breaking_threshold": gap})
        bounces[gap] = mean_bounce(engine, 0.05)
    assert bounces[0.02] < bounces[0.01] - 0.05
    assert bounces[0.001] == pytest.approx(mean_bounce(engine, 2.5), abs=0.03)


def test_default_friction_combines_to_the_product(engine: PybulletEngine) -> None:
    """A ball thrown flat along the plane slides first: its deceleration is mu g, with mu the
    product of both bodies' default friction, 0.5 x 0.5 = 0.25."""
    engine.spawn([ground(), BodyGroup("sphere", (RADIUS,), ["a"], poses_at([0, 0, RADIUS]),
                                      twists=np.array([[2.0, 0, 0, 0, 0, 0]]))])
    engine.step(12)
    speed = engine.get_states(["a"])[1][0, 0]
    assert (2.0 - speed) / (12 * engine.timestep) / GRAVITY == pytest.approx(0.5**2, abs=0.01)


def test_bodies_share_one_mesh_look_per_shape_size_and_colour(engine: PybulletEngine) -> None:
    """Spawns give each body a cached mesh as its look: PyBullet would otherwise build one
    per body from the collision shape (a convex hull, 0.4 ms per sphere)."""
    engine.spawn([balls([f"b{i}" for i in range(20)], grid(20), rgba=(1, 0, 0, 1)),
                  balls(["c"], [5, 5, 1], rgba=(0, 0, 1, 1))])
    looks = {engine._bc.getVisualShapeData(body_id(engine, n))[0][2] for n in ("b0", "b19", "c")}
    assert looks == {5}  # GEOM_MESH
    assert engine._bc.getVisualShapeData(body_id(engine, "c"))[0][7] == pytest.approx((0, 0, 1, 1))
    assert len(engine._shapes) == 1


def test_properties_are_what_pybullet_simulates(engine: PybulletEngine) -> None:
    """Defaults included; static bodies have no mass; a model weighs all its links."""
    engine.set_params({"default_static_friction": 0.7})
    engine.spawn([ground(), balls(["plain"], [0, 0, 1]),
                  balls(["own"], [1, 0, 1], mass=3.0, friction=0.9, restitution=0.3),
                  BodyGroup("box", (0.1, 0.2, 0.3), ["box"], poses_at([2, 0, 1]))])
    arm, _ = engine.load_model("urdf", ARM_URDF, None, "m/", fixed_base=False)
    names = ["ground", "plain", "own", "box", arm.name]
    ball_mass = 1000 * 4 / 3 * math.pi * RADIUS**3
    np.testing.assert_allclose(engine.properties(names), [
        [math.nan, 0.7, 0.0], [ball_mass, 0.5, 0.0], [3.0, 0.9, 0.3],
        [1000 * 0.2 * 0.4 * 0.6, 0.5, 0.0], [2.5, 0.5, 0.0]])
    engine.update(["plain"], BodyProperties(mass=2.0, restitution=0.5))
    engine.set_params({"default_friction": 0.2, "default_restitution": 0.6,
                       "default_static_restitution": 0.1})
    np.testing.assert_allclose(engine.properties(names)[:4], [
        [math.nan, 0.7, 0.1], [2.0, 0.2, 0.5], [3.0, 0.9, 0.3],
        [1000 * 0.2 * 0.4 * 0.6, 0.2, 0.6]])
    assert engine.properties([]).shape == (0, 3)
    with pytest.raises(NotFoundError, match="nobody"):
        engine.properties(["nobody"])


def test_clear_empties_the_world_and_keeps_params(engine: PybulletEngine) -> None:
    engine.set_params({"gravity": [0, 0, -3.0]})
    engine.spawn([ground(), balls(["a"], [0, 0, 1])])
    engine.clear()
    assert engine._bc.getNumBodies() == 0
    assert engine._bc.getPhysicsEngineParameters()["gravityAccelerationZ"] == pytest.approx(-3)
    engine.spawn([balls(["a"], [0, 0, 1])])
    assert engine.get_states(["a"])[0][0, 2] == pytest.approx(1)


# -- physics -----------------------------------------------------------------------------
def test_ccd_stops_a_fast_ball_tunnelling(engine: PybulletEngine) -> None:
    engine.set_params({"gravity": [0, 0, 0], "pybullet.ccd_swept_sphere_radius": 0.01})
    wall = BodyGroup("box", (0.005, 1, 1), ["wall"], poses_at([0, 0, 0]), static=True)
    shot = BodyGroup("sphere", (0.01,), ["shot"], poses_at([-0.5, 0, 0]),
                     twists=np.array([[60.0, 0, 0, 0, 0, 0]]))
    engine.spawn([wall, shot])
    engine.step(60)
    assert engine.get_states(["shot"])[0][0, 0] < 0


def test_bounds_apply_to_moving_bodies_only(engine: PybulletEngine) -> None:
    """Limits are inclusive, and a static body set far away is scenery, not a divergence."""
    engine.spawn([ground(), balls(["a"], [[0, 0, 1]])])
    engine.set_states(["ground"], poses_at([0, 0, -5e6]), None)
    engine.set_states(["a"], poses_at([-1e6, 0, 1]), np.array([[0, 0, 0, 1e5, 0, 0]]))
    assert engine.state_within(1e6, 1e5)
    assert not engine.state_within(1e6, 0.99e5)
    assert not engine.state_within(0.99e6, 1e5)


# -- rewinding: stop sets every body back, then reset_dynamics -----------------------------
def overlapping_scene() -> list[BodyGroup]:
    """Spheres, boxes and a capsule made overlapping on a plane: they burst apart, collide
    and tumble, so any difference in the contact state shows within a few hundred steps."""
    def turned(positions: Any, angles: list[float]) -> np.ndarray:
        poses = poses_at(positions)
        poses[:, 3], poses[:, 6] = np.sin(np.divide(angles, 2)), np.cos(np.divide(angles, 2))
        return poses

    return [ground(),
            balls([f"s{i}" for i in range(4)], [[0, 0, 0.05], [0.08, 0, 0.05],
                                                [0.04, 0.06, 0.1], [0, 0.02, 0.14]]),
            BodyGroup("box", (0.05, 0.04, 0.03), ["b0", "b1"],
                      turned([[0.1, 0.05, 0.05], [0.14, 0.08, 0.09]], [0.4, 0.7])),
            BodyGroup("capsule", (0.03, 0.06), ["cap"], turned([[0.05, 0.1, 0.12]], [1.2]),
                      twists=np.array([[0.2, 0, 0, 0, 0, 1.0]]))]


def created_states(groups: list[BodyGroup]) -> tuple[list[str], np.ndarray, np.ndarray]:
    """Names, poses and twists as the World keeps them for a stop: what spawn was given."""
    names = [n for g in groups for n in g.names]
    twists = [g.twists if g.twists is not None else np.zeros((len(g), 6)) for g in groups]
    return names, np.vstack([g.poses for g in groups]), np.vstack(twists)


def test_a_rewound_world_replays_its_first_run(engine: PybulletEngine) -> None:
    """Bit for bit, however long the run before the rewind was, with a model, an update and
    a deleted body before the first run (Bullet kept contacts and their warm starts)."""
    groups = overlapping_scene()
    engine.spawn(groups)
    engine.update(["s1", "b0"], BodyProperties(mass=0.3, friction=0.9, rgba=(1, 0, 0, 1)))
    engine.delete(["s2"])
    arm, _ = engine.load_model("urdf", ARM_URDF, None, "m/", fixed_base=False)
    engine.set_states([arm.name], poses_at([0.3, 0.3, 0.3]), None)
    names, poses, twists = created_states(groups)
    keep = [k for k, name in enumerate(names) if name != "s2"]
    names = [*(names[k] for k in keep), arm.name]
    poses, twists = np.vstack([poses[keep], poses_at([0.3, 0.3, 0.3])]), np.vstack(
        [twists[keep], np.zeros(6)])

    def run(steps: int) -> tuple[np.ndarray, np.ndarray]:
        engine.step(steps)
        states = engine.get_states(names)
        engine.set_states(names, poses, twists)
        engine.restore_joints()  # as the World's stop does, before the rewind
        engine.reset_dynamics()
        return states

    first = run(600)
    run(100)
    again = run(600)
    np.testing.assert_array_equal(first[0], again[0])
    np.testing.assert_array_equal(first[1], again[1])
    assert np.abs(first[0][:, :3] - poses[:, :3]).max() > 0.3  # they burst apart


def test_a_rebuild_keeps_joint_states_and_restore_joints_brings_them_back(
        engine: PybulletEngine) -> None:
    arm, _ = engine.load_model("urdf", ARM_URDF, None, "m/", fixed_base=False)
    pose, twist = engine.get_states([arm.name])
    engine.update([arm.name], BodyProperties(mass=5.0, friction=0.3))
    engine.set_joint_states(["m/hinge"], np.array([0.5]), np.array([2.0]))
    engine.reset_dynamics()
    assert engine.get_joint_states(["m/hinge"])[0].tolist() == [0.5]
    assert engine.get_joint_states(["m/hinge"])[1].tolist() == [2.0]
    engine.step(10)
    engine.set_states([arm.name], pose, twist)
    engine.restore_joints()
    engine.reset_dynamics()
    uid = body_id(engine, arm.name)
    assert engine._bc.getJointState(uid, 0)[:2] == (0.0, 0.0)
    np.testing.assert_allclose(engine.properties([arm.name]), [[5.0, 0.3, 0.0]])
    np.testing.assert_array_equal(engine.get_states([arm.name])[0], pose)


def test_a_model_mass_scales_every_link(engine: PybulletEngine) -> None:
    """As MuJoCo does: the whole model weighs what update says, its links in proportion."""
    arm, _ = engine.load_model("urdf", ARM_URDF, None, "m/", fixed_base=False)
    uid = body_id(engine, arm.name)
    for mass in (5.0, 1.25):
        engine.update([arm.name], BodyProperties(mass=mass))
        assert engine.properties([arm.name])[0, 0] == pytest.approx(mass)
        base, link = (engine._bc.getDynamicsInfo(uid, k) for k in (-1, 0))
        assert base[0] == pytest.approx(0.8 * mass) and link[0] == pytest.approx(0.2 * mass)
        assert base[2] == pytest.approx([0.01 * 0.4 * mass] * 3)


def test_rewinding_an_empty_world_does_nothing(engine: PybulletEngine) -> None:
    engine.reset_dynamics()
    assert engine.rebuilds == 0 and engine.state_within(1e6, 1e5)


# -- models ------------------------------------------------------------------------------
def test_load_urdf_text(engine: PybulletEngine) -> None:
    engine.spawn([ground()])
    (info,) = engine.load_model("urdf", TINY_URDF, None, "m1/", fixed_base=False)
    assert (info.name, info.shape, info.source, info.static) == ("m1/crate", "model", "model",
                                                                 False)
    assert info.mass == pytest.approx(2.0)
    engine.set_states([info.name], poses_at([0, 0, 1]), None)
    engine.step(480)
    assert engine.get_states([info.name])[0][0, 2] == pytest.approx(0.1, abs=0.005)
    engine.delete([info.name])


def test_a_model_name_in_use_is_refused(engine: PybulletEngine) -> None:
    engine.load_model("urdf", TINY_URDF, None, "m/", fixed_base=False)
    before = engine._maker.known_ids()
    with pytest.raises(NameNotUniqueError, match="m/crate"):
        engine.load_model("urdf", TINY_URDF, None, "m/", fixed_base=False)
    assert engine._maker.known_ids() == before and list(engine.bodies) == ["m/crate"]


@pytest.mark.parametrize(("text", "message"), [
    ("<robot name='x'><link name='a'></robot>", "well-formed"),
    ("<mujoco/>", "root element"),
    ("<robot name='x'><link name='a'><collision><geometry><box size='a b'/></geometry>"
     "</collision></link><joint/></robot>", "could not load"),
])
def test_a_broken_urdf_is_refused_and_changes_nothing(
        engine: PybulletEngine, text: str, message: str) -> None:
    engine.spawn([ground(), balls(["a"], [0, 0, 1])])
    before = engine._maker.known_ids()
    with pytest.raises(InvalidArgumentError, match=message):
        engine.load_model("urdf", text, None, "")
    assert engine._maker.known_ids() == before and set(engine.bodies) == {"ground", "a"}


def test_load_mjcf_gives_one_entity_per_body(engine: PybulletEngine, tmp_path: Any) -> None:
    path = tmp_path / "pair.xml"
    path.write_text(TINY_MJCF)
    infos = engine.load_model("mjcf", None, str(path), "p_")
    names = [i.name for i in infos]
    assert len(names) == 3 and {"p_ball", "p_ball_1"} <= set(names)
    assert [i.static for i in infos if i.name.startswith("p_ball")] == [False, False]
    engine.step(240)
    assert engine.get_states(["p_ball"])[0][0, 2] == pytest.approx(0.1, abs=0.005)


def test_unknown_format_and_missing_file(engine: PybulletEngine) -> None:
    with pytest.raises(FeatureUnsupportedError):
        engine.load_model("sdf", "<sdf/>", None, "")
    with pytest.raises(InvalidArgumentError, match="cannot read"):
        engine.load_model("urdf", None, "/nonexistent/model.urdf", "")


# -- memory: rebuilding the world --------------------------------------------------------
def seen(engine: PybulletEngine, names: list[str]) -> tuple[Any, ...]:
    """What the protocol (and the engine's own bookkeeping) can tell of these bodies."""
    bc = engine._bc
    looks = [bc.getVisualShapeData(body_id(engine, n))[0][7] for n in names]
    dynamics = [bc.getDynamicsInfo(body_id(engine, n), -1) for n in names]
    kept = [(b.static, b.shape, b.size, b.mass, b.friction, b.restitution, b.rgba,
             b.follows_friction, b.follows_restitution) for b in map(engine.bodies.get, names)]
    return *engine.get_states(names), looks, dynamics, kept


def test_a_rebuild_keeps_every_body_as_it_was(engine: PybulletEngine, monkeypatch: Any) -> None:
    monkeypatch.setattr("galton.daemon.engines.pybullet.rebuild.REBUILD_AFTER", 10)
    engine.set_params({"pybullet.collision_margin": 0.003,
                       "pybullet.ccd_swept_sphere_radius": 0.02})
    engine.spawn([ground(), balls(["ball"], [0, 0, 0.3]),
                  balls(["own"], [1, 0, 1], friction=0.9, restitution=0.3, mass=0.2,
                        rgba=(1, 0, 0, 1)),
                  BodyGroup("box", (0.1, 0.2, 0.05), ["crate"], poses_at([0, 1, 1]),
                            twists=[[1, 0, 2, 3, -1, 0.5]]),
                  BodyGroup("capsule", (0.05, 0.1), ["pill"], poses_at([1, 1, 1])),
                  BodyGroup("box", (0.5, 0.5, 0.1), ["step"], poses_at([3, 3, 0.1]),
                            static=True)])
    engine.update(["pill"], BodyProperties(mass=3.0, rgba=(0, 0, 1, 1)))
    engine.step(40)  # turned, moving bodies
    junk = [f"j{i}" for i in range(20)]
    engine.spawn([balls(junk, grid(20, z=4.0))])
    engine.delete(junk[:5])
    assert engine.rebuilds == 0
    kept = ["ground", "ball", "own", "crate", "pill", "step"]
    before = seen(engine, kept)
    engine.delete(junk[5:])  # 20 removed >= max(10, 2 * 6 left)
    assert engine.rebuilds == 1 and engine._removed == 0
    after = seen(engine, kept)
    assert list(engine.bodies) == kept and engine._bc.getNumBodies() == len(kept)
    assert np.array_equal(after[0], before[0]) and np.array_equal(after[1], before[1])
    assert after[2:] == before[2:]
    engine.set_params({"default_friction": 0.3})  # followers still follow, others keep theirs
    friction = {n: engine._bc.getDynamicsInfo(body_id(engine, n), -1)[1] for n in kept}
    assert friction["ball"] == pytest.approx(0.3) and friction["own"] == pytest.approx(0.9)
    engine.step(480)  # the ball rests on the kept plane, the others fell or stood
    poses, twists = engine.get_states(["ball"])
    assert poses[0, 2] == pytest.approx(RADIUS, abs=0.002) and np.abs(twists[0]).max() < 0.01
    assert engine.state_within(1e6, 1e5) and not engine.held


def test_churn_rebuilds_every_five_thousand_deleted(engine: PybulletEngine) -> None:
    engine.spawn([ground()])
    names = [f"b{i}" for i in range(1000)]
    for round_ in range(1, 12):
        engine.spawn([balls(names, grid(1000))])
        engine.delete(names)
        assert engine.rebuilds == round_ // 5 and engine._removed == round_ % 5 * 1000
    assert list(engine.bodies) == ["ground"] and engine._bc.getNumBodies() == 1


def test_a_world_with_a_model_is_not_rebuilt(engine: PybulletEngine, monkeypatch: Any) -> None:
    monkeypatch.setattr("galton.daemon.engines.pybullet.rebuild.REBUILD_AFTER", 10)
    engine.spawn([ground()])
    (info,) = engine.load_model("urdf", TINY_URDF, None, "m/", fixed_base=False)
    junk = [f"j{i}" for i in range(20)]
    engine.spawn([balls(junk, grid(20, z=4.0))])
    uid = body_id(engine, info.name)
    engine.delete(junk)
    assert engine.rebuilds == 0 and engine._removed == 20
    assert body_id(engine, info.name) == uid and set(engine.bodies) == {"ground", info.name}
    engine.delete([info.name])  # the model gone, the count so far brings the rebuild
    assert engine.rebuilds == 1 and set(engine.bodies) == {"ground"}


def resident_bytes() -> int:
    """This process's resident memory: tracemalloc cannot see Bullet's own heap."""
    with open("/proc/self/statm", encoding="ascii") as statm:
        return int(statm.read().split()[1]) * PAGE_BYTES


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="reads Linux's /proc")
def test_clearing_the_world_frees_what_it_held(engine: PybulletEngine) -> None:
    """`reset all` clears the world. PyBullet's createVisualShape keeps the lists of every
    mesh it is given, so meshes made afresh for each world leaked 17.5 kB per clear of these
    four shapes (26 MB over the cycles); shared meshes keep RSS flat (0 measured)."""
    def cycle() -> None:
        engine.spawn([ground(), balls([f"b{i}" for i in range(5)], grid(5)),
                      BodyGroup("box", (0.1, 0.1, 0.1), ["box"], poses_at([0, 1, 1])),
                      BodyGroup("capsule", (0.05, 0.1), ["pill"], poses_at([1, 1, 1]))])
        engine.step(5)
        engine.clear()

    for _ in range(200):  # the allocator's and the caches' first growth
        cycle()
    gc.collect()
    objects, before = len(gc.get_objects()), resident_bytes()
    cycles = 1500
    for _ in range(cycles):
        cycle()
    grown = resident_bytes() - before
    gc.collect()
    assert len(gc.get_objects()) - objects < 100
    assert grown < cycles * 500, f"{grown / cycles:.0f} bytes per clear"
