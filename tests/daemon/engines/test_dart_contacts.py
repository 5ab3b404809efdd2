"""DART's contacts and shapes as gz-physics sets them up, through the engine's public
interface: where a ball comes to rest, the smaller friction of a pair, the collision
detector Gazebo installs (and FCL's, which turns a capsule into a sphere), the shapes it
reports, and parameters that say where they come from."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support.engine_bodies import at, engine_fixture, ground, seconds, slide

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup, InvalidArgumentError
from galton.protocol.mesh import box_mesh

RADIUS = 0.05


ENGINE = "dart"
engine = engine_fixture(ENGINE)


def test_a_dropped_ball_comes_to_rest_on_the_ground(engine: Engine) -> None:
    engine.spawn([ground(), BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 0.3]))])
    seconds(engine, 1.5)  # Gazebo's restitution 0: it lands and stays
    poses, twists = engine.get_states(["ball"])
    assert poses[0, 2] == pytest.approx(RADIUS, abs=3e-4)  # sunk a little, being pushed out
    assert np.abs(twists[0]).max() < 1e-3


def test_a_pair_slides_on_the_smaller_of_its_two_frictions() -> None:
    """DART takes the smaller friction of a pair (ODE, as Webots sets it up, takes the
    scenery's): a slippery box on a rough ground slides as far as a rough box on a
    slippery ground, and Coulomb's v² / (2 μ g) says how far."""
    slippery = slide(ENGINE, 1.0, 0.2)
    assert slippery == pytest.approx(slide(ENGINE, 0.2, 1.0), abs=1e-6)
    assert slippery == pytest.approx(slide(ENGINE, 0.2, 0.2), abs=1e-6)
    assert slippery == pytest.approx(4.0 / (2 * 0.2 * 9.8), rel=0.05)
    assert slide(ENGINE, 1.0, 1.0) == pytest.approx(4.0 / (2 * 1.0 * 9.8), rel=0.05)


def cube_on_capsule(detector: str, along: float) -> float:
    """Where a small cube dropped on a capsule lying on the ground, ``along`` its axis from
    its centre, comes to rest (its height), under one collision detector."""
    engine = create_engine("dart")
    try:
        engine.set_params({"dart.collision_detector": detector})
        lying = at([0, 0, 0.3])
        lying[0, 3:] = [math.sin(math.pi / 4), 0, 0, math.cos(math.pi / 4)]  # axis along y
        engine.spawn([ground(), BodyGroup("capsule", (0.05, 0.2), ["pill"], lying),
                      BodyGroup("box", (0.02, 0.02, 0.02), ["cube"], at([0, along, 0.5]))])
        seconds(engine, 0.3)
        poses = engine.get_states(["pill", "cube"])[0]
        assert poses[0, 2] == pytest.approx(RADIUS, abs=2e-3)  # the capsule, on its side
        return float(poses[1, 2])
    finally:
        engine.close()


def test_odes_detector_keeps_a_capsule_fcl_loses_its_ends() -> None:
    """gz-physics installs ODE's detector in every world; DART's own FCL turns a capsule
    into a sphere, so a cube dropped near the capsule's end falls past it there."""
    on_top = 2 * RADIUS + 0.02
    assert cube_on_capsule("ode", 0.0) == pytest.approx(on_top, abs=5e-3)
    assert cube_on_capsule("ode", 0.18) == pytest.approx(on_top, abs=5e-3)
    assert cube_on_capsule("fcl", 0.0) == pytest.approx(on_top, abs=5e-3)
    assert cube_on_capsule("fcl", 0.18) < on_top - 0.03


def test_switching_the_detector_keeps_the_world(engine: Engine) -> None:
    """A new detector rebuilds DART's collision world, not the scene: every body stays where
    and as fast as it was, and goes on colliding."""
    engine.spawn([ground(), BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 0.3]))])
    engine.step(100)
    before = engine.get_states(["ball"])
    engine.set_params({"dart.collision_detector": "fcl"})
    assert engine.get_params()["dart.collision_detector"] == "fcl"
    for was, now in zip(before, engine.get_states(["ball"]), strict=True):
        assert np.array_equal(was, now)
    seconds(engine, 1.0)
    assert engine.get_states(["ball"])[0][0, 2] == pytest.approx(RADIUS, abs=1e-3)


def test_spawned_shapes_are_reported_as_spawned(engine: Engine) -> None:
    """Half sizes as the wire's SIZE_LAYOUT; a mesh as the box around it, in float32 (DART
    loads a mesh through Assimp's float32)."""
    vertices, faces = box_mesh((0.4, 0.2, 0.1))
    engine.spawn([BodyGroup("sphere", (0.1,), ["s"], at([0, 0, 1])),
                  BodyGroup("box", (0.1, 0.2, 0.3), ["b"], at([1, 0, 1])),
                  BodyGroup("cylinder", (0.1, 0.2), ["c"], at([2, 0, 1])),
                  BodyGroup("capsule", (0.1, 0.2), ["p"], at([3, 0, 1])),
                  BodyGroup("mesh", (0.4, 0.2, 0.1), ["m"], at([4, 0, 1]),
                            vertices=vertices, faces=faces)])
    shapes = engine.shapes(["s", "b", "c", "p", "m"])
    assert [[(kind, tuple(size)) for kind, size, _ in body] for body in shapes] == [
        [("sphere", (0.1,))], [("box", (0.1, 0.2, 0.3))], [("cylinder", (0.1, 0.2))],
        [("capsule", (0.1, 0.2))], [("mesh", pytest.approx((0.4, 0.2, 0.1), abs=1e-7))]]
    for body in shapes:
        assert tuple(body[0][2]) == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)


def test_a_ball_rests_on_a_mesh_slab(engine: Engine) -> None:
    vertices, faces = box_mesh((0.5, 0.5, 0.1))
    engine.spawn([BodyGroup("mesh", (0.5, 0.5, 0.1), ["slab"], at([0, 0, 0.2]), static=True,
                            vertices=vertices, faces=faces),
                  BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 0.6]))])
    seconds(engine, 1.5)
    assert engine.get_states(["ball"])[0][0, 2] == pytest.approx(0.3 + RADIUS, abs=3e-4)


def test_a_bad_parameter_is_refused_and_changes_nothing(engine: Engine) -> None:
    with pytest.raises(InvalidArgumentError, match=r"dart\.collision_detector must be one of"):
        engine.set_params({"timestep": 0.002, "dart.collision_detector": "magic"})
    with pytest.raises(InvalidArgumentError, match=r"dart\.sleep must be true or false"):
        engine.set_params({"dart.sleep": "yes"})
    params = engine.get_params()
    assert (params["timestep"], params["dart.collision_detector"]) == (0.001, "ode")
    assert engine.timestep == 0.001


def test_every_parameter_says_where_its_default_comes_from(engine: Engine) -> None:
    params = engine.capabilities().params
    for name, spec in params.items():
        assert any(word in spec["source"] for word in ("Gazebo", "DART", "SDF")), name
    assert "gz-physics" in params["dart.collision_detector"]["source"]
    assert "1 ms" in params["timestep"]["source"]
