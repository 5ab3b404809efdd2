"""ODE's robots, meshes, frames, rays and snapshot format, through the engine's public
interface: a URDF's joints and link frames (a link reports its URDF frame, not the centre of
mass ODE's body sits at), targets, a trimesh a ball rests on, rays against links and
meshes, what ODE cannot do refused as such, and the snapshot's own format."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from support.engine_bodies import LEVER, at, engine_fixture, ground, seconds

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup, FeatureUnsupportedError, InvalidArgumentError
from galton.protocol.mesh import box_mesh

RADIUS = 0.05


engine = engine_fixture("ode")


def hold(engine: Engine, target: float) -> None:
    engine.set_joint_targets(["l_hinge"], "position", np.array([target]), np.array([200.0]),
                             np.array([20.0]), np.array([np.inf]))


def test_a_urdf_loads_its_links_and_joints_as_written(engine: Engine) -> None:
    infos = engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    assert [(i.name, i.shape, i.static, i.model) for i in infos] == [
        ("l_base", "model", True, "l_base"), ("l_arm", "link", False, "l_base")]
    assert infos[1].mass == 1.0
    (hinge,) = engine.joints()
    assert (hinge.name, hinge.type, hinge.parent, hinge.child) == (
        "l_hinge", "revolute", "l_base", "l_arm")
    assert (hinge.axis, hinge.lower, hinge.upper, hinge.effort_limit) == (
        (0.0, 1.0, 0.0), -1.0, 1.0, 100.0)


def test_a_link_reports_its_urdf_frame_not_its_centre_of_mass(engine: Engine) -> None:
    """ODE puts a body at its centre of mass (0.2 m out along the arm); the engine reports
    the link's own frame, on the hinge, turned by the joint's angle."""
    engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    np.testing.assert_allclose(engine.get_states(["l_arm"])[0][0], [0, 0, 1, 0, 0, 0, 1],
                               atol=1e-12)
    engine.set_joint_states(["l_hinge"], np.array([0.5]), np.array([0.0]))
    np.testing.assert_allclose(engine.get_states(["l_arm"])[0][0],
                               [0, 0, 1, 0, np.sin(0.25), 0, np.cos(0.25)], atol=1e-12)
    (box,) = engine.shapes(["l_arm"])[0]
    assert box[0] == "box" and box[1] == pytest.approx((0.2, 0.025, 0.025))
    assert box[2][:3] == pytest.approx((0.2, 0.0, 0.0))  # in the link's frame


def test_a_position_target_holds_the_lever_against_gravity(engine: Engine) -> None:
    engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    hold(engine, -0.3)
    seconds(engine, 2.0)
    position, velocity, effort = engine.get_joint_states(["l_hinge"])
    # A PD law holds it a little short of the target: kp (target - q) = the arm's weight
    # times its lever arm (1 kg · 9.81 · 0.2 m · cos 0.3).
    assert position[0] == pytest.approx(-0.3 + 1.87 / 200.0, abs=1e-3)
    assert abs(velocity[0]) < 1e-6
    assert effort[0] == pytest.approx(-9.81 * 0.2 * np.cos(0.3), rel=0.02)


@pytest.mark.parametrize(("mode", "target", "stop"), [
    ("position", 1.0, 1.0), ("position", -1.0, -1.0), ("velocity", 5.0, 1.0),
    ("velocity", -5.0, -1.0)])
def test_a_target_at_the_limit_leaves_the_hinge_at_its_stop(
        engine: Engine, mode: str, target: float, stop: float) -> None:
    """A target at (or driving past) the joint's limit is one the World accepts; DART holds
    the arm there, and so does ODE: at a stop ODE makes a powered motor a constant push of
    its whole FMax, and an unbounded damper's (1e30) once threw this arm, its centre of mass
    0.2 m off the hinge, off at 1e24 m/s (issue 46)."""
    engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    engine.set_joint_targets(["l_hinge"], mode, np.array([target]), np.array([200.0]),
                             np.array([20.0]), np.array([np.inf]))
    seconds(engine, 1.0)
    position, velocity, _ = engine.get_joint_states(["l_hinge"])
    assert position[0] == pytest.approx(stop, abs=0.02)
    assert abs(velocity[0]) < 1e-3
    assert engine.state_within(1e4, 1e3)


def test_a_ball_rests_on_a_trimesh_and_rays_find_its_top(engine: Engine) -> None:
    vertices, faces = box_mesh((0.5, 0.5, 0.1))
    engine.spawn([BodyGroup("mesh", (0.5, 0.5, 0.1), ["slab"], at([0, 0, 0.2]), static=True,
                            vertices=vertices, faces=faces),
                  BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 0.6]))])
    seconds(engine, 1.5)
    assert engine.get_states(["ball"])[0][0, 2] == pytest.approx(0.3 + RADIUS, abs=1e-4)
    hits = engine.raycast(np.array([[0.3, 0.3, 2.0], [0.0, 0.0, 2.0], [0.3, 0.3, 2.0]]),
                          np.array([[0, 0, -1.0], [0, 0, -1.0], [0, 0, 1.0]]), 10.0)
    assert hits.hit.tolist() == [True, True, False]
    assert hits.entity == ["slab", "ball", ""]
    np.testing.assert_allclose(hits.point[0], [0.3, 0.3, 0.3], atol=1e-6)  # OPCODE: float32
    np.testing.assert_allclose(hits.normal[0], [0, 0, 1], atol=1e-9)
    assert hits.distance[1] == pytest.approx(2.0 - 0.3 - 2 * RADIUS, abs=1e-3)


def test_rays_hit_a_link_where_it_is_and_stop_at_their_length(engine: Engine) -> None:
    engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    down = np.array([[0, 0, -1.0]])
    hits = engine.raycast(np.array([[0.3, 0, 3.0]]), down, 10.0)
    assert hits.entity == ["l_arm"] and hits.point[0] == pytest.approx([0.3, 0, 1.025])
    assert not engine.raycast(np.array([[0.3, 0, 3.0]]), down, 1.5).hit[0]  # 1.975 away
    engine.set_joint_states(["l_hinge"], np.array([0.8]), np.array([0.0]))
    assert not engine.raycast(np.array([[0.3, 0, 3.0]]), down, 10.0).hit[0]  # turned away


def test_what_ode_cannot_do_is_refused_as_unsupported(engine: Engine) -> None:
    with pytest.raises(FeatureUnsupportedError, match="rendering"):
        engine.render([])
    with pytest.raises(FeatureUnsupportedError, match="urdf models, not 'mjcf'"):
        engine.load_model("mjcf", "<mujoco/>", None, "m_")
    features = engine.capabilities().features
    assert "render" not in features and "raycast" in features
    assert engine.capabilities().model_formats == ("urdf",)


def mixed_world(engine: Engine) -> list[str]:
    vertices, faces = box_mesh((0.2, 0.2, 0.1))
    engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    engine.spawn([ground(),
                  BodyGroup("mesh", (0.2, 0.2, 0.1), ["crate"], at([1.0, 0, 0.3]),
                            vertices=vertices, faces=faces),
                  BodyGroup("sphere", (RADIUS,), ["ball"], at([0.3, 0, 2.0]), restitution=0.9),
                  BodyGroup("capsule", (0.03, 0.1), ["pill"], at([-0.5, 0, 0.4]))])
    hold(engine, 0.4)
    engine.set_wrenches(["crate"], np.array([[1.0, 0, 0, 0, 0, 0.5]]), None)
    return ["l_arm", "crate", "ball", "pill"]


def test_snapshot_step_restore_step_is_bit_identical(engine: Engine) -> None:
    names = mixed_world(engine)
    seconds(engine, 0.1)
    data = engine.snapshot()
    assert (data["format"], data["version"], data["engine"]) == ("galton-ode-snapshot", 1, "ode")
    seconds(engine, 0.3)
    went_on = engine.get_states(names)
    copy = create_engine("ode")
    try:
        copy.restore(data)
        seconds(copy, 0.3)
        for mine, theirs in zip(went_on, copy.get_states(names), strict=True):
            assert np.array_equal(mine, theirs)
        assert copy.get_params() == engine.get_params()
    finally:
        copy.close()


def restored(data: dict[str, Any]) -> None:
    copy = create_engine("ode")
    try:
        copy.restore(data)
    finally:
        copy.close()


def test_a_snapshot_of_another_format_or_version_is_refused(engine: Engine) -> None:
    mixed_world(engine)
    data = engine.snapshot()
    for key, value in (("format", "galton-dart-1"), ("version", 2), ("version", "1")):
        with pytest.raises(InvalidArgumentError, match="not an ode snapshot"):
            restored({**data, key: value})
    with pytest.raises(InvalidArgumentError):
        restored({**data, "params": {**data["params"], "ode.erp": 7.0}})
    with pytest.raises(InvalidArgumentError):
        restored({k: v for k, v in data.items() if k != "bodies"})
    restored(data)  # the untouched one restores
