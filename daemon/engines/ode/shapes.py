"""A URDF link's collision shapes as ODE collides them, and as ``get_shapes`` tells them:
box, sphere and cylinder as ODE's own; a mesh as the box of its bounds (ODE trimeshes are
left out of models: a model link's mesh collides as that box)."""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np

from galton.daemon.engines.base import Shape
from galton.daemon.engines.ode import frames
from galton.daemon.engines.ode.spawn import Body
from galton.protocol import InvalidArgumentError


def model_shapes(bodies: Sequence[Body]) -> list[list[Shape]]:
    """Each model body's collision shapes as loaded (``link_shapes``, kept on the body)."""
    return [list(body.link_shapes) for body in bodies]


def link_shapes(link: Any) -> list[tuple[str, tuple[float, ...], frames.Frame]]:
    """The link's collision shapes as (shape, half sizes, frame in the link)."""
    shapes = []
    for collision in link.collisions:
        origin = frames.from_matrix(np.asarray(collision.origin if collision.origin is not None
                                               else np.eye(4), dtype=float))
        geometry = collision.geometry
        if geometry.box is not None:
            shapes.append(("box", tuple(float(s) / 2 for s in geometry.box.size), origin))
        elif geometry.sphere is not None:
            shapes.append(("sphere", (float(geometry.sphere.radius),), origin))
        elif geometry.cylinder is not None:
            shapes.append(("cylinder", (float(geometry.cylinder.radius),
                                        float(geometry.cylinder.length) / 2), origin))
        elif geometry.mesh is not None:
            shapes.append(_mesh_box(geometry.mesh, origin))
    return shapes


def _mesh_box(mesh: Any, origin: frames.Frame) -> tuple[str, tuple[float, ...], frames.Frame]:
    import trimesh

    filename = str(mesh.filename)
    if filename.startswith("file://"):
        filename = filename[len("file://"):]
    if not os.path.isfile(filename):
        raise InvalidArgumentError(f"the URDF's mesh {mesh.filename!r} is not there")
    try:
        bounds = np.asarray(trimesh.load(filename, force="mesh").bounds, dtype=float)
    except Exception as exc:
        raise InvalidArgumentError(f"the URDF's mesh {filename!r} does not load: {exc}") \
            from exc
    scale = np.ones(3) if mesh.scale is None else np.broadcast_to(
        np.asarray(mesh.scale, dtype=float), (3,))
    low, high = bounds[0] * scale, bounds[1] * scale
    half = np.maximum(np.abs(high - low) / 2, 1e-4)
    centre = frames.compose(origin, ((low + high) / 2, frames.IDENTITY[1]))
    return "box", tuple(half.tolist()), centre
