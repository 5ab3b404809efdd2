"""Mesh bodies and spawn's own inertia on every engine: a ball rests on a static mesh box
at its top, a moving mesh box rests on the ground, a snapshot replays a mesh world bit for
bit, a refused mesh changes nothing, and a ball given the paper's inertia of 0.1 kg m²
spins up far slower down an incline."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from support import snapshot
from support.worlds import clean

from galton.client import Client, InvalidArgumentError, body_group, meshes, plane, spheres
from galton.protocol import BodyGroup
from galton.protocol import mesh as mesh_wire
from galton.protocol.mesh import box_mesh

HALF = (0.2, 0.2, 0.1)
TOP = 0.5 + HALF[2]
RADIUS = 0.05
REST_ATOL = 0.005  # m: a contact's penetration or margin, on every engine


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        yield client


def slab(**options: Any) -> Any:
    vertices, faces = box_mesh(HALF)
    return meshes(["slab"], [[0, 0, 0.5]], vertices, faces, static=True, **options)


def test_a_ball_rests_on_a_static_mesh_box_at_its_top(world: Client, engine: str) -> None:
    world.spawn(slab(), spheres(["ball"], [[0.05, 0.02, TOP + 0.2]], RADIUS))
    states = world.step_and_read(round(1.5 / world.status().timestep), ["ball"])
    assert states.poses[0, 2] == pytest.approx(TOP + RADIUS, abs=REST_ATOL)
    entity = next(e for e in world.list() if e.name == "slab")
    assert entity.shape == "mesh" and entity.size == pytest.approx(HALF)


def test_a_moving_mesh_box_rests_on_the_ground(world: Client, engine: str) -> None:
    vertices, faces = box_mesh(HALF)
    world.spawn(plane(), meshes(["crate"], [[0, 0, 0.4]], vertices, faces))
    states = world.step_and_read(round(1.5 / world.status().timestep), ["crate"])
    assert states.poses[0, 2] == pytest.approx(HALF[2], abs=REST_ATOL)


def test_a_snapshot_replays_a_mesh_world_and_delete_takes_it(world: Client,
                                                              engine: str) -> None:
    world.spawn(slab(), spheres(["ball"], [[0.05, 0.02, TOP + 0.1]], RADIUS))
    world.step(20)
    world.snapshot("mesh")
    first = world.step_and_read(120, ["ball"]).poses.copy()
    world.restore("mesh")
    assert np.array_equal(world.step_and_read(120, ["ball"]).poses, first)
    world.delete(["slab"])
    assert [e.name for e in world.list()] == ["ball"]


def _bad_meshes() -> list[dict[str, Any]]:
    vertices = box_mesh(HALF)[0]
    return [{"faces": mesh_wire.pack_faces(np.array([[0, 1, 8]]))},  # index out of range
            {"faces": mesh_wire.pack_faces(np.array([[0, 1, 1]]))},  # a repeated vertex
            {"faces": b"\x00" * 10},  # not whole triangles
            {"vertices": mesh_wire.pack_vertices(vertices * [1, 1, 0])},  # flat
            {"vertices": mesh_wire.pack_vertices(np.full((8, 3), math.nan))},
            {"vertices": mesh_wire.pack_vertices(np.zeros((20_001, 3)))},  # too many
            {"vertices": mesh_wire.pack_vertices(vertices)[:-8]},  # not whole rows
            {"size": [0.1, 0.1, 0.1]}, {"inertia": [0.1, 0.1]}, {"inertia": [1, 1, 5]}]


@pytest.mark.parametrize("bad", _bad_meshes(), ids=lambda bad: next(iter(bad)))
def test_a_refused_mesh_changes_nothing(world: Client, engine: str,
                                        bad: dict[str, Any]) -> None:
    world.spawn(plane())
    before = snapshot(world)
    group = {**slab().to_wire(), **bad}
    with pytest.raises(InvalidArgumentError):
        world.call("spawn", {"groups": [group]})
    snapshot(world).assert_same(before)


def test_a_ball_of_inertia_0_1_spins_up_slower_down_an_incline(world: Client,
                                                               engine: str) -> None:
    """The paper's Gazebo draft gave its 1 kg, r 0.045 m ball an inertia of 0.1 kg m²
    (about 120 times a solid ball's): rolling, its spin grows 1 + I/(m r²) times slower."""
    tilt = math.radians(20)
    turn = np.array([math.sin(tilt / 2), 0.0, 0.0, math.cos(tilt / 2)])
    world.spawn(BodyGroup("box", (1.0, 1.0, 0.05), ["ramp"],
                          np.array([[0.0, 0.0, 0.0, *turn]]), static=True, friction=1.0))
    up = np.array([0.0, -math.sin(tilt), math.cos(tilt)])  # the ramp's normal
    starts = [np.array([x, 0.0, 0.0]) + (0.05 + 0.045 + 0.001) * up for x in (-0.3, 0.3)]
    solid, heavy = [spheres([name], [at], 0.045, mass=1.0, friction=1.0, **extra)
                    for name, at, extra in (("solid", starts[0], {}),
                                            ("heavy", starts[1], {"inertia": [0.1] * 3}))]
    world.spawn(solid, heavy)
    spins = np.linalg.norm(world.step_and_read(round(0.5 / world.status().timestep),
                                               ["solid", "heavy"]).twists[:, 3:], axis=1)
    assert spins[0] > 10.0  # rad/s: the solid ball rolls (5/7 g sin θ: about 27 rad/s)
    assert spins[1] < 0.1 * spins[0]


def test_a_snapshot_keeps_a_bodys_own_inertia(world: Client, engine: str) -> None:
    """A spun box with its own inertia: a restore replays it bit for bit, so the snapshot
    carried the inertia (a shape's would precess differently)."""
    spin = np.array([[0.0, 0.0, 0.0, 3.0, 1.0, 0.5]])
    world.spawn(body_group("box", (0.1, 0.05, 0.02), ["top"], [[0, 0, 5]], twists=spin,
                           inertia=[0.004, 0.01, 0.012]))
    world.set_params({"gravity": [0.0, 0.0, 0.0]})
    world.snapshot("spun")
    first = world.step_and_read(100, ["top"]).twists.copy()
    world.restore("spun")
    assert np.array_equal(world.step_and_read(100, ["top"]).twists, first)
