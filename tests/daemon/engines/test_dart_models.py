"""DART's robots, through the engine's public interface: a URDF's links and joints as
dartpy reads them, link frames, the three kinds of joint target, a joint's limit held, and
formats DART cannot read refused without touching the world."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.engine_bodies import LEVER, seconds

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import (
    BodyGroup,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NameNotUniqueError,
)

ARM_WEIGHT_TORQUE = 1.0 * 9.8 * 0.2  # the arm's weight on its 0.2 m lever, level


@pytest.fixture
def engine() -> Iterator[Engine]:
    made = create_engine("dart")
    made.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    yield made
    made.close()


def target(engine: Engine, mode: str, value: float, kp: float = 200.0, kd: float = 20.0,
           most: float = np.inf) -> None:
    engine.set_joint_targets(["l_hinge"], mode, np.array([value]), np.array([kp]),
                             np.array([kd]), np.array([most]))


def test_a_urdf_loads_its_links_and_joints_as_written(engine: Engine) -> None:
    (hinge,) = engine.joints()
    assert (hinge.name, hinge.type, hinge.parent, hinge.child, hinge.mode) == (
        "l_hinge", "revolute", "l_base", "l_arm", "none")
    assert (hinge.axis, hinge.lower, hinge.upper, hinge.effort_limit, hinge.velocity_limit) \
        == ((0.0, 1.0, 0.0), -1.0, 1.0, 100.0, 10.0)


def test_a_link_reports_its_urdf_frame_turned_by_its_joint(engine: Engine) -> None:
    np.testing.assert_allclose(engine.get_states(["l_arm"])[0][0], [0, 0, 1, 0, 0, 0, 1],
                               atol=1e-12)
    engine.set_joint_states(["l_hinge"], np.array([0.5]), np.array([0.0]))
    np.testing.assert_allclose(engine.get_states(["l_arm"])[0][0],
                               [0, 0, 1, 0, np.sin(0.25), 0, np.cos(0.25)], atol=1e-12)
    (box,) = engine.shapes(["l_arm"])[0]
    assert box[0] == "box" and tuple(box[1]) == pytest.approx((0.2, 0.025, 0.025))
    assert tuple(box[2][:3]) == pytest.approx((0.2, 0.0, 0.0))


def test_a_position_target_holds_the_lever_against_gravity(engine: Engine) -> None:
    target(engine, "position", -0.3)
    seconds(engine, 2.0)
    position, velocity, effort = engine.get_joint_states(["l_hinge"])
    held = ARM_WEIGHT_TORQUE * np.cos(0.3)
    assert position[0] == pytest.approx(-0.3 + held / 200.0, abs=1e-3)  # PD: a little short
    assert abs(velocity[0]) < 1e-6
    assert effort[0] == pytest.approx(-held, rel=0.02)


def test_a_velocity_target_turns_the_lever_at_that_rate(engine: Engine) -> None:
    target(engine, "velocity", 0.5, kp=0.0, kd=50.0)
    seconds(engine, 0.5)
    position, velocity, _ = engine.get_joint_states(["l_hinge"])
    # A damper of 50 N·m·s/rad: the weight, turning the arm the same way, adds its torque
    # over 50 to the rate.
    rate = 0.5 + ARM_WEIGHT_TORQUE * np.cos(position[0]) / 50.0
    assert velocity[0] == pytest.approx(rate, abs=0.005)
    assert position[0] == pytest.approx(0.5 * velocity[0], abs=0.02)  # at that rate from 0


def test_an_effort_target_against_the_weight_lifts_or_lets_fall(engine: Engine) -> None:
    """The arm's weight pulls it down (positive angle about +y); a torque above it lifts."""
    target(engine, "effort", -3.0)
    seconds(engine, 0.2)
    assert engine.get_joint_states(["l_hinge"])[1][0] < 0  # lifting
    target(engine, "effort", -1.0)
    seconds(engine, 0.2)
    assert engine.get_joint_states(["l_hinge"])[2][0] == pytest.approx(-1.0)


def test_a_target_at_the_limit_leaves_the_hinge_at_its_stop(engine: Engine) -> None:
    """The weight presses the arm into its upper stop, and the stop holds it."""
    target(engine, "position", 1.0)
    seconds(engine, 1.0)
    position, velocity, _ = engine.get_joint_states(["l_hinge"])
    assert position[0] == pytest.approx(1.0, abs=0.02) and abs(velocity[0]) < 1e-3


def test_formats_dart_cannot_read_are_refused_and_the_world_is_unchanged(
        engine: Engine) -> None:
    before = engine.get_states(["l_arm"])
    with pytest.raises(FeatureUnsupportedError, match="not 'sdf'"):
        engine.load_model("sdf", "<sdf/>", None, "s_")
    with pytest.raises(InvalidArgumentError, match="mjcf model does not parse"):
        engine.load_model("mjcf", "<robot/>", None, "m_")
    with pytest.raises(NameNotUniqueError, match="'l_base'"):
        engine.load_model("urdf", LEVER, None, "l_", fixed_base=True)
    assert [j.name for j in engine.joints()] == ["l_hinge"]
    for was, now in zip(before, engine.get_states(["l_arm"]), strict=True):
        assert np.array_equal(was, now)
    engine.spawn([BodyGroup("sphere", (0.05,), ["ball"], np.array([[2.0, 0, 1, 0, 0, 0, 1]]))])
    engine.step(10)
