"""The DART engine on its own, in-process: what is DART's own, beyond what every engine
must do (galton.daemon.engines.check, test_engine_check.py): Gazebo's set-up, how DART
combines a pair's surfaces, its contacts, and the guard that keeps ODE from aborting."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from galton.daemon.engines.dart.engine import DartEngine
from galton.protocol import (
    BodyGroup,
    FeatureUnsupportedError,
    InvalidArgumentError,
)
from galton.protocol import mesh as mesh_wire
from galton.protocol.mesh import box_mesh

RADIUS = 0.05


@pytest.fixture
def engine() -> Iterator[DartEngine]:
    eng = DartEngine()
    yield eng
    eng.close()


def at(*positions: list[float]) -> np.ndarray:
    out = np.zeros((len(positions), 7))
    out[:, :3] = positions
    out[:, 6] = 1.0
    return out


def plane(**options: object) -> BodyGroup:
    return BodyGroup("plane", (5.0, 5.0), ["ground"], at([0, 0, 0]), static=True, **options)


def test_it_starts_as_gazebo_harmonic_runs_dart(engine: DartEngine) -> None:
    """ODE's collision detector, a 1 ms step, SDF's gravity and surface defaults."""
    params = engine.get_params()
    assert engine.timestep == 0.001
    assert params["dart.collision_detector"] == "ode"
    assert params["gravity"] == [0.0, 0.0, -9.8]
    assert (params["default_friction"], params["default_restitution"]) == (1.0, 0.0)
    detector = engine._world.getConstraintSolver().getCollisionDetector()
    assert detector.getType() == "ode"
    caps = engine.capabilities()
    assert "raycast" not in caps.features and "render" not in caps.features
    assert all("default" in spec and "unit" in spec for spec in caps.params.values())


def test_a_turned_spinning_body_glides_along_its_world_velocity(engine: DartEngine) -> None:
    """dartpy 6.20's free joint holds world-frame velocities: the twist set is the twist
    DART simulates, whatever the body's orientation and spin."""
    engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    turned = at([0, 0, 5])
    turned[0, 3:] = [math.sin(0.4), 0, 0, math.cos(0.4)]
    engine.spawn([BodyGroup("box", (0.1, 0.2, 0.3), ["crate"], turned,
                            twists=np.array([[1.0, 0, 0, 0, 0, 2.0]]))])
    engine.step(100)
    poses, twists = engine.get_states(["crate"])
    node = engine._bodies["crate"].node
    np.testing.assert_allclose(twists[0, :3], node.getLinearVelocity(), atol=1e-12)
    np.testing.assert_allclose(twists[0, 3:], node.getAngularVelocity(), atol=1e-12)
    np.testing.assert_allclose(poses[0, :3], [0.1, 0, 5], atol=1e-9)


def test_ray_casts_and_rendering_are_refused_as_unsupported(engine: DartEngine) -> None:
    with pytest.raises(FeatureUnsupportedError, match="ray casts"):
        engine.raycast(np.zeros((1, 3)), np.array([[0, 0, -1.0]]), 10.0)
    with pytest.raises(FeatureUnsupportedError, match="rendering"):
        engine.render([])


def _bounce(engine: DartEngine, ball: float, ground: float) -> float:
    """Rebound over impact speed of a ball dropped from 0.5 m."""
    engine.spawn([plane(restitution=ground),
                  BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 0.5]), restitution=ball)])
    fastest_up = 0.0
    for _ in range(600):
        engine.step(1)
        fastest_up = max(fastest_up, float(engine.get_states(["ball"])[1][0, 2]))
    impact = math.sqrt(2 * 9.8 * (0.5 - RADIUS))
    engine.clear()
    return fastest_up / impact


def test_restitution_is_the_product_of_the_pairs_values(engine: DartEngine) -> None:
    """DART multiplies a pair's restitutions: 0.8 on a 1.0 ground bounces about 0.8,
    0.8 on a 0.5 ground about 0.4, and the SDF default 0 not at all."""
    assert _bounce(engine, 0.8, 1.0) == pytest.approx(0.8, abs=0.05)
    assert _bounce(engine, 0.8, 0.5) == pytest.approx(0.4, abs=0.05)
    assert _bounce(engine, 0.0, 0.0) < 0.02


def test_a_resting_balls_contact_carries_its_weight_along_the_normal(
        engine: DartEngine) -> None:
    engine.spawn([plane(), BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, RADIUS]),
                                     mass=2.0)])
    engine.step(500)
    firsts, seconds, points, normals, forces, depths = engine.contacts(["ball"])
    assert len(firsts) == 1 and {firsts[0], seconds[0]} == {"ball", "ground"}
    down = np.array([0, 0, -1.0]) if firsts[0] == "ball" else np.array([0, 0, 1.0])
    np.testing.assert_allclose(normals[0], down, atol=1e-9)  # from the first to the second
    assert forces[0] == pytest.approx(2.0 * 9.8, rel=0.02)
    assert 0 <= depths[0] < 0.005 and abs(points[0, 2]) < 0.005


def test_a_world_sent_astronomically_far_is_diverged_not_stepped(engine: DartEngine) -> None:
    """ODE aborts the process on such a bounding box: the engine must not step it."""
    engine.spawn([plane(), BodyGroup("sphere", (RADIUS,), ["ball"], at([0, 0, 1]))])
    engine.set_states(["ball"], at([4e299, 0, 1]), None)
    engine.step(3)
    assert engine.state_within(1e6, 1e5) is False
    engine.set_states(["ball"], at([0, 0, 1]), np.zeros((1, 6)))
    engine.reset_dynamics()
    engine.step(3)
    assert engine.state_within(1e6, 1e5) is True


MJCF = """<mujoco model="pair"><worldbody>
  <geom type="plane" size="5 5 0.1"/>
  <body name="crate" pos="0 0 1"><joint type="free"/>
    <geom type="box" size=".1 .1 .1" mass="2"/></body>
  <body name="arm" pos="1 0 1"><joint name="hinge" type="hinge" axis="0 1 0"/>
    <geom type="capsule" size=".05 .2" mass="1"/></body>
</worldbody></mujoco>"""


def test_an_mjcf_loads_one_model_per_top_level_body_and_one_for_the_world(
        engine: DartEngine) -> None:
    infos = engine.load_model("mjcf", MJCF, None, "m/")
    assert [(i.name, i.shape, i.static) for i in infos] == [
        ("m/crate", "model", False), ("m/arm", "model", False), ("m/world", "model", True)]
    joints = {j.name: (j.type, j.parent, j.child) for j in engine.joints()}
    assert joints["m/hinge"] == ("revolute", "", "m/arm")
    engine.step(500)  # the crate falls onto the world's plane and stays on it
    assert engine.get_states(["m/crate"])[0][0, 2] == pytest.approx(0.1, abs=0.01)


def test_a_snapshot_of_another_engine_is_refused(engine: DartEngine) -> None:
    with pytest.raises(InvalidArgumentError, match="not a DART snapshot"):
        engine.restore({"format": "galton-pybullet-1"})
    with pytest.raises(InvalidArgumentError, match="malformed DART snapshot"):
        engine.restore({"format": "galton-dart-1", "params": {}, "items": [{"kind": "body"}]})


def test_a_mesh_is_loaded_in_float32_and_a_damaged_one_is_not_restored(
        engine: DartEngine) -> None:
    """dartpy makes a MeshShape only by loading a file (meshes.py): the shape holds the
    vertices as Assimp's float32; a snapshot carries the float64 ones, checked on restore."""
    vertices, faces = box_mesh((0.2, 0.2, 0.1))
    vertices = vertices + 0.1 / 3  # not a float32 number
    engine.spawn([BodyGroup("mesh", (0.3, 0.3, 0.2), ["slab"], at([0, 0, 0.5]), static=True,
                            vertices=vertices, faces=faces)])
    box = engine._bodies["slab"].node.getShapeNode(0).getShape().getBoundingBox()
    assert np.array_equal(box.getMax(), vertices.max(axis=0).astype(np.float32))
    data = engine.snapshot()
    data["items"][0]["faces"] = mesh_wire.pack_faces(np.array([[0, 1, 8]]))
    copy = DartEngine()
    try:
        with pytest.raises(InvalidArgumentError, match="faces"):
            copy.restore(data)
    finally:
        copy.close()
