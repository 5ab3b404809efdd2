"""ODE's contacts as Webots sets them up, through the engine's public interface: where a
ball comes to rest, whose surface decides a contact's friction and bounce (the scenery's
against the scenery, the larger of two moving bodies'), soft contacts (ERP/CFM), the
bounce threshold, the contact-joint cap, and parameters that say where they come from."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from support.engine_bodies import at, engine_fixture, ground, seconds, slide

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup, InvalidArgumentError

RADIUS = 0.05


ENGINE = "ode"
engine = engine_fixture(ENGINE)


def ball(name: str, position: list[float], **options: Any) -> BodyGroup:
    return BodyGroup("sphere", (RADIUS,), [name], at(position), **options)


def rest_height(params: dict[str, Any]) -> float:
    engine = create_engine("ode")
    try:
        engine.set_params({"ode.auto_disable": False, **params})
        engine.spawn([ground(), ball("ball", [0, 0, 0.3])])
        seconds(engine, 1.5)
        poses, twists = engine.get_states(["ball"])
        assert np.abs(twists[0]).max() < 1e-3  # at rest, not still bouncing
        return float(poses[0, 2])
    finally:
        engine.close()


def test_a_dropped_ball_rests_on_the_ground_sunk_as_deep_as_its_soft_contact_lets_it() -> None:
    """Webots' soft contact (softCFM 0.001 at 32 ms) lets a ball sink a few µm; a contact
    ten times softer lets it sink deeper, and neither lets it sink a millimetre."""
    webots = rest_height({})
    softer = rest_height({"ode.contact_soft_cfm": 0.01})
    assert RADIUS - 1e-4 < webots < RADIUS
    assert RADIUS - 1e-3 < softer < webots


def test_against_the_scenery_the_scenerys_friction_decides() -> None:
    """Webots: a contact with a static body takes the static body's surface, so a box's
    own friction does not change how far it slides on the ground; the ground's does."""
    rough, slippery = slide(ENGINE, 1.0, 0.2), slide(ENGINE, 0.2, 1.0)
    assert rough == pytest.approx(slide(ENGINE, 1.0, 1.0), abs=1e-9)
    assert slippery == pytest.approx(slide(ENGINE, 0.2, 0.2), abs=1e-9)
    # Coulomb: v² / (2 μ g), 0.20 m at μ 1 and 1.02 m at μ 0.2 (it stops before a second).
    assert rough == pytest.approx(4.0 / (2 * 1.0 * 9.81), rel=0.1)
    assert slippery == pytest.approx(4.0 / (2 * 0.2 * 9.81), rel=0.1)


def bounce(first: float, second: float, second_static: bool) -> float:
    """Rebound over impact speed of a ball of bounce ``first`` dropped on a body of bounce
    ``second``: the static ground, or a heavy moving block (its top 0.1 m up) resting on a
    static ground; it falls 0.5 m - its radius either way."""
    engine = create_engine("ode")
    try:
        if second_static:
            engine.spawn([ground(restitution=second), ball("ball", [0, 0, 0.5],
                                                           restitution=first)])
        else:
            engine.spawn([ground(restitution=0.0),
                          BodyGroup("box", (0.5, 0.5, 0.05), ["block"], at([0, 0, 0.05]),
                                    mass=1000.0, restitution=second),
                          ball("ball", [0, 0, 0.6], restitution=first)])
        down = up = 0.0
        for _ in range(round(0.6 / engine.timestep)):
            engine.step(1)
            speed = float(engine.get_states(["ball"])[1][0, 2])
            down, up = min(down, speed), max(up, speed)
        assert -down == pytest.approx(np.sqrt(2 * 9.81 * (0.5 - RADIUS)), rel=0.05)  # fell
        return up / -down
    finally:
        engine.close()


def test_against_the_scenery_the_scenerys_bounce_decides() -> None:
    assert bounce(0.9, 0.1, second_static=True) < 0.15
    assert bounce(0.1, 0.9, second_static=True) == pytest.approx(0.87, abs=0.04)


def test_between_two_moving_bodies_the_larger_bounce_wins() -> None:
    """Webots takes the larger value of a pair of moving bodies: a lively ball on a dead
    block bounces as a dead ball on a lively block, and as well as a lively pair."""
    lively_ball = bounce(0.8, 0.0, second_static=False)
    lively_block = bounce(0.0, 0.8, second_static=False)
    assert lively_ball == pytest.approx(lively_block, abs=0.02)
    assert lively_ball == pytest.approx(bounce(0.8, 0.8, second_static=False), abs=0.02)
    assert lively_ball > 0.7 and bounce(0.0, 0.0, second_static=False) < 0.2


def rebound_speed(bounce_velocity: float) -> float:
    """Fastest upward speed of a bouncy ball landing at about 0.6 m/s."""
    engine = create_engine("ode")
    try:
        engine.set_params({"ode.bounce_velocity": bounce_velocity})
        engine.spawn([ground(restitution=1.0), ball("ball", [0, 0, RADIUS + 0.02],
                                                    restitution=1.0)])
        up = 0.0
        for _ in range(round(0.2 / engine.timestep)):
            engine.step(1)
            up = max(up, float(engine.get_states(["ball"])[1][0, 2]))
        return up
    finally:
        engine.close()


def test_an_impact_slower_than_the_bounce_velocity_does_not_bounce() -> None:
    assert rebound_speed(0.01) > 0.4  # Webots' 1 cm/s threshold: it bounces back
    assert rebound_speed(1.0) < 0.1  # under 1 m/s it stays down (the soft contact's push)


def test_a_pair_gets_at_most_max_contacts_contact_joints(engine: Engine) -> None:
    """A box flat on the ground touches it at its four corners; with Webots'
    MAX_CONTACT_JOINTS lowered to 1, one contact carries its whole weight."""
    for cap, expected in ((10, 4), (1, 1)):
        engine.clear()
        engine.set_params({"ode.max_contacts": cap, "ode.auto_disable": False})
        engine.spawn([ground(), BodyGroup("box", (0.1, 0.1, 0.05), ["box"], at([0, 0, 0.05]),
                                          mass=3.0)])
        seconds(engine, 0.3)
        contacts = engine.contacts(["box"])
        assert len(contacts.first) == expected
        assert contacts.force.sum() == pytest.approx(3.0 * 9.81, rel=0.02)


def test_the_world_erp_and_cfm_are_webots_and_a_bad_value_changes_nothing(
        engine: Engine) -> None:
    engine.set_params({"ode.erp": 0.5, "ode.cfm": 1e-4})
    assert (engine.get_params()["ode.erp"], engine.get_params()["ode.cfm"]) == (0.5, 1e-4)
    with pytest.raises(InvalidArgumentError, match=r"ode\.erp"):
        engine.set_params({"ode.cfm": 1e-3, "ode.erp": 1.5})
    with pytest.raises(InvalidArgumentError, match=r"ode\.stepper"):
        engine.set_params({"ode.stepper": "fast"})
    with pytest.raises(InvalidArgumentError, match=r"unknown parameter 'ode\.warp'"):
        engine.set_params({"ode.warp": 1})
    params = engine.get_params()
    assert (params["ode.erp"], params["ode.cfm"], params["ode.stepper"]) == (0.5, 1e-4, "world")


def test_every_parameter_says_where_its_default_comes_from(engine: Engine) -> None:
    """Each default is Webots' (or ODE's) or says why the daemon's differs."""
    params = engine.capabilities().params
    assert set(params) >= {"ode.erp", "ode.cfm", "ode.contact_soft_cfm", "ode.stepper"}
    for name, spec in params.items():
        source = spec["source"]
        assert any(word in source for word in ("Webots", "ODE", "the daemon's")), name
    assert "WorldInfo.ERP" in params["ode.erp"]["source"]
    assert "softCFM" in params["ode.contact_soft_cfm"]["source"]
    assert params["timestep"]["source"].startswith("the daemon's")
