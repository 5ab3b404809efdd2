"""A DART model link's collision shapes in its body node's frame (``get_shapes``): DART's
own box, sphere, cylinder and capsule (full lengths turned into half sizes); any other
shape (a mesh, an ellipsoid) as the box DART keeps around it."""

from __future__ import annotations

from typing import Any

import dartpy as dart
import numpy as np

from galton.daemon.engines.base import Shape
from galton.daemon.engines.dart import frames


def node_shapes(node: Any) -> list[Shape]:
    found: list[Shape] = []
    for k in range(node.getNumShapeNodes()):
        shape_node = node.getShapeNode(k)
        if shape_node.hasCollisionAspect():
            found.append(_shape(shape_node.getShape(), shape_node.getRelativeTransform()))
    return found


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

