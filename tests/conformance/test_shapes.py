"""get_shapes: each entity's collision shapes in its own frame, on every engine; a mesh with
its triangles where the daemon knows them (spawned meshes always; a loaded model's where
the engine keeps them), else flagged as its box."""

from __future__ import annotations

import numpy as np
import pytest
from support.models import ROBOTS, load, load_robot

from galton.client import Client, ShapeInfo, body_group, meshes, spheres
from galton.protocol import FeatureUnsupportedError, NotFoundError
from galton.protocol.mesh import box_mesh

# Engines that keep a loaded model's mesh triangles (the others tell such a mesh as its box).
TELLS_MODEL_MESHES = ("mujoco", "pybullet", "dart")

URDF = """<robot name="crate"><link name="base">
  <inertial><origin xyz="0.05 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.4 0.6"/></geometry></collision>
</link></robot>"""


def test_a_primitive_is_its_own_shape_at_its_origin(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[1.0, 2.0, 3.0]], 0.25, static=True))
    sim.spawn(body_group("cylinder", (0.1, 0.3), ["can"], [[0.0, 0.0, 1.0]], static=True))
    shapes = sim.get_shapes()
    assert list(shapes) == ["ball", "can"]
    [ball], [can] = shapes["ball"], shapes["can"]
    assert (ball.kind, can.kind) == ("sphere", "cylinder")
    np.testing.assert_allclose(ball.size, [0.25, 0.0, 0.0])
    np.testing.assert_allclose(can.size, [0.1, 0.3, 0.0])
    np.testing.assert_allclose(can.pose, [0, 0, 0, 0, 0, 0, 1])
    with pytest.raises(NotFoundError, match="did you mean 'ball'"):
        sim.get_shapes(["bal"])


def test_a_urdf_crate_is_one_box_of_its_size(sim: Client) -> None:
    caps = sim.capabilities()
    if "urdf" not in caps.model_formats:
        pytest.skip(f"{caps.engine} loads no URDF")
    [name] = sim.load_model("urdf", text=URDF, prefix="u_")
    if "model_shapes" not in caps.features:  # the engine says so, and answers so
        with pytest.raises(FeatureUnsupportedError):
            sim.get_shapes([name])
        return
    [crate] = sim.get_shapes([name])[name]
    assert crate.kind == "box"
    np.testing.assert_allclose(crate.size, [0.1, 0.2, 0.3], atol=1e-6)
    # In the link's frame, not its centre of mass's.
    np.testing.assert_allclose(crate.pose[:3], [0.0, 0.0, 0.1], atol=1e-6)
    np.testing.assert_allclose(np.abs(crate.pose[3:]), [0, 0, 0, 1], atol=1e-6)


def _crate() -> tuple[np.ndarray, np.ndarray]:
    """A box off its body's origin: not the box that its reach about the origin makes."""
    vertices, faces = box_mesh((0.1, 0.05, 0.08))
    return vertices + np.array([0.03, -0.02, 0.01]), faces


def test_a_spawned_mesh_is_told_with_its_triangles_and_keeps_them(sim: Client) -> None:
    if "mesh" not in sim.capabilities().body_shapes:
        pytest.skip("this engine spawns no mesh")
    vertices, faces = _crate()
    sim.spawn(meshes(["m1", "m2"], [[0, 0, 1], [1, 0, 1]], vertices, faces, static=True),
              spheres(["ball"], [[0, 1, 1]], 0.1, static=True))
    shapes = sim.get_shapes()
    [m1], [m2], [ball] = shapes["m1"], shapes["m2"], shapes["ball"]
    assert (m1.kind, m1.boxed, ball.vertices, ball.boxed) == ("mesh", False, None, False)
    np.testing.assert_allclose(m1.vertices, vertices)
    np.testing.assert_array_equal(m1.faces, faces)
    np.testing.assert_allclose(m1.pose, [0, 0, 0, 0, 0, 0, 1])
    assert m2.vertices is m1.vertices  # one mesh, sent once for both bodies
    result = sim.call("get_shapes", {"names": ["m1", "m2", "ball"]})
    assert (result["meshes"], len(result["mesh_vertices"])) == ([0, 0, -1], 1)
    assert "meshes" not in sim.call("get_shapes", {"names": ["ball"]})  # as before meshes
    # A snapshot's blob and a fork carry them.
    blob = sim.snapshot(blob=True).blob
    sim.delete(["m1", "m2"])
    sim.restore(blob=blob)
    np.testing.assert_allclose(_mesh_of(sim, "m2").vertices, vertices)
    sim.fork_world("side")
    try:
        np.testing.assert_allclose(_mesh_of(sim.world("side"), "m1").vertices, vertices)
    finally:
        sim.delete_world("side")


def _mesh_of(sim: Client, name: str) -> ShapeInfo:
    [shape] = sim.get_shapes([name])[name]
    return shape


def test_a_robots_mesh_links_are_their_triangles_or_flagged_boxes(sim: Client,
                                                                  engine: str) -> None:
    caps = sim.capabilities()
    if "model_shapes" not in caps.features or "urdf" not in caps.model_formats:
        pytest.skip(f"{engine} tells no loaded model's shapes")
    names = load(sim, "urdf", path=ROBOTS["kuka"])  # collision meshes: STL files
    rows = [shape for entity in sim.get_shapes(names).values() for shape in entity]
    told = [shape for shape in rows if shape.kind == "mesh" and not shape.boxed]
    assert len(told) == (len(rows) if engine in TELLS_MODEL_MESHES else 0)
    for shape in told:  # in the row's frame, inside the box the row gives
        assert shape.faces is not None and shape.faces.max() < len(shape.vertices)
        assert np.all(np.abs(shape.vertices) <= np.asarray(shape.size) + 1e-6)


def test_a_robots_mesh_triangles_fill_the_engines_own_box(sim: Client, engine: str) -> None:
    """The triangles sent are where the engine collides: they fill the box the engine keeps
    around the mesh (the row's size: DART's own box, PyBullet's hull's), and placed by the
    link's pose and the row's they span PyBullet's own box of the link (getAABB) within its
    collision margin. MuJoCo's box of a link is its mesh geoms' boxes turned, looser."""
    if engine not in ("pybullet", "dart"):
        pytest.skip(f"{engine}'s own box of a link is not its triangles' box")
    names = load_robot(sim, "kuka")  # sent as text: the daemon makes its file names whole
    shapes = sim.get_shapes(names)
    rows = [shape for name in names for shape in shapes[name]]
    assert rows and all(shape.vertices is not None for shape in rows)
    for shape in rows:
        assert shape.vertices is not None
        np.testing.assert_allclose(shape.vertices.max(axis=0), shape.size, atol=1e-3)
        np.testing.assert_allclose(shape.vertices.min(axis=0), -np.asarray(shape.size),
                                   atol=1e-3)
    if engine == "dart":
        return  # DART tells no box of a loaded link (get_bounds: FEATURE_UNSUPPORTED)
    bounds, poses = sim.get_bounds(names), sim.get_states(names).poses
    for row, name in enumerate(names):
        every = np.concatenate([_placed(poses[row], shape.pose, shape.vertices)
                                for shape in shapes[name] if shape.vertices is not None])
        found = np.concatenate([every.min(axis=0), every.max(axis=0)])
        np.testing.assert_allclose(found, bounds[name], atol=0.03, err_msg=name)


def _placed(body: np.ndarray, row: np.ndarray, vertices: np.ndarray) -> np.ndarray:
    """Vertices in the world: turned and moved by the row's pose, then the body's."""
    for pose in (row, body):
        vertices = _turn(pose[3:], vertices) + pose[:3]
    return vertices


def _turn(quat: np.ndarray, points: np.ndarray) -> np.ndarray:
    x, y, z, w = quat
    matrix = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return points @ matrix.T
