"""A MuJoCo body's colliding geoms as the protocol's shapes (``get_shapes``), and the
triangles of those that are meshes.

A primitive geom is its kind, half sizes and pose in the body's frame. Any other geom (a
mesh, a height field, an ellipsoid) is the box MuJoCo keeps around it (``geom_aabb``, in
the geom's frame), posed at the box's centre; a mesh geom's triangles are MuJoCo's compiled
mesh (``mesh_vert``, in the geom's frame) moved into that same frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines.base import Shape, ShapeMesh
from galton.protocol.vocabulary import SIZE_LAYOUT

# MuJoCo's geom types as the protocol's shapes (sizes already half sizes, as SIZE_LAYOUT).
_GEOM = mujoco.mjtGeom
_GEOM_KINDS = {int(_GEOM.mjGEOM_PLANE): "plane", int(_GEOM.mjGEOM_SPHERE): "sphere",
               int(_GEOM.mjGEOM_CAPSULE): "capsule", int(_GEOM.mjGEOM_CYLINDER): "cylinder",
               int(_GEOM.mjGEOM_BOX): "box"}


def colliding_geoms(model: Any, body: int) -> np.ndarray:
    """The body's geoms that collide (contype or conaffinity set), in MuJoCo's order."""
    return np.flatnonzero((model.geom_bodyid == body)
                          & ((model.geom_contype | model.geom_conaffinity) != 0))


def body_shapes(model: Any, bodies: Sequence[int]) -> list[list[Shape]]:
    return [[geom_shape(model, int(g)) for g in colliding_geoms(model, body)]
            for body in bodies]


def body_meshes(model: Any, bodies: Sequence[int]) -> list[dict[int, ShapeMesh]]:
    """Each body's mesh geoms' triangles, by their index in ``body_shapes``' list; geoms of
    one mesh asset share its vertex and face arrays when their boxes agree."""
    made: dict[tuple[int, bytes], ShapeMesh] = {}
    found: list[dict[int, ShapeMesh]] = []
    for body in bodies:
        meshes: dict[int, ShapeMesh] = {}
        for row, geom in enumerate(colliding_geoms(model, body)):
            asset = int(model.geom_dataid[geom])
            if int(model.geom_type[geom]) != int(_GEOM.mjGEOM_MESH) or asset < 0:
                continue
            centre = np.array(model.geom_aabb[geom][:3], dtype=float)
            key = (asset, centre.tobytes())
            if key not in made:
                made[key] = _mesh_triangles(model, asset, centre)
            meshes[row] = made[key]
        found.append(meshes)
    return found


def _mesh_triangles(model: Any, asset: int, centre: np.ndarray) -> ShapeMesh:
    """A mesh asset's vertices (about its box's centre) and faces."""
    first, count = int(model.mesh_vertadr[asset]), int(model.mesh_vertnum[asset])
    vertices = np.array(model.mesh_vert[first:first + count], dtype=float) - centre
    start, faces = int(model.mesh_faceadr[asset]), int(model.mesh_facenum[asset])
    return vertices, np.array(model.mesh_face[start:start + faces], dtype=np.int64)


def geom_shape(model: Any, geom: int) -> Shape:
    quat = model.geom_quat[geom]  # w x y z
    rotation = (float(quat[1]), float(quat[2]), float(quat[3]), float(quat[0]))
    position = model.geom_pos[geom]
    kind = _GEOM_KINDS.get(int(model.geom_type[geom]))
    if kind is not None:
        width = len(SIZE_LAYOUT[kind])
        size = tuple(float(v) for v in model.geom_size[geom][:width])
        return kind, size, (*map(float, position), *rotation)
    box = model.geom_aabb[geom]  # centre and half sizes in the geom's frame
    matrix = np.empty(9)
    mujoco.mju_quat2Mat(matrix, quat)
    centre = position + matrix.reshape(3, 3) @ box[:3]
    return "mesh", tuple(float(v) for v in box[3:]), (*map(float, centre), *rotation)
