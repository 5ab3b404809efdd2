"""A DART model link's collision shapes in its body node's frame (``get_shapes``): DART's
own box, sphere, cylinder and capsule (full lengths turned into half sizes); any other
shape (a mesh, an ellipsoid) as the box DART keeps around it, a mesh file's triangles beside
it (mesh_files.py), in that box's frame."""

from __future__ import annotations

from typing import Any

import dartpy as dart
import numpy as np

from galton.daemon.engines.base import Shape, ShapeMesh
from galton.daemon.engines.dart import frames
from galton.daemon.engines.dart.mesh_files import MeshFiles


def node_shapes(node: Any) -> list[Shape]:
    return [_shape(shape, transform) for shape, transform in _colliding(node)]


def node_meshes(node: Any, files: MeshFiles) -> dict[int, ShapeMesh]:
    """The triangles of the node's mesh shapes by row, about the centre of DART's box."""
    found: dict[int, ShapeMesh] = {}
    for row, (shape, _) in enumerate(_colliding(node)):
        if shape.getType() != dart.dynamics.MeshShape.getStaticType():
            continue
        mesh = files.get(str(shape.getMeshPath()), tuple(shape.getScale()))
        if mesh is not None:
            box = shape.getBoundingBox()
            centre = (np.asarray(box.getMin(), dtype=float)
                      + np.asarray(box.getMax(), dtype=float)) / 2
            found[row] = (mesh[0] - centre, mesh[1])
    return found


def _colliding(node: Any) -> list[tuple[Any, Any]]:
    shape_nodes = (node.getShapeNode(k) for k in range(node.getNumShapeNodes()))
    return [(sn.getShape(), sn.getRelativeTransform()) for sn in shape_nodes
            if sn.hasCollisionAspect()]


def _shape(shape: Any, transform: Any) -> Shape:
    matrix = np.asarray(transform.matrix(), dtype=float)
    position = matrix[:3, 3]
    quat = tuple(float(v) for v in frames.matrix_to_quat(matrix[:3, :3]))
    kind = shape.getType()
    if kind == dart.dynamics.BoxShape.getStaticType():
        return "box", tuple(float(v) / 2 for v in shape.getSize()), (*position, *quat)
    if kind == dart.dynamics.SphereShape.getStaticType():
        return "sphere", (float(shape.getRadius()),), (*position, *quat)
    if kind == dart.dynamics.CylinderShape.getStaticType():
        return ("cylinder", (float(shape.getRadius()), float(shape.getHeight()) / 2),
                (*position, *quat))
    if kind == dart.dynamics.CapsuleShape.getStaticType():
        return ("capsule", (float(shape.getRadius()), float(shape.getHeight()) / 2),
                (*position, *quat))
    box = shape.getBoundingBox()
    low, high = np.asarray(box.getMin(), dtype=float), np.asarray(box.getMax(), dtype=float)
    centre = position + matrix[:3, :3] @ ((low + high) / 2)
    return "mesh", tuple(float(v) for v in (high - low) / 2), (*centre, *quat)

