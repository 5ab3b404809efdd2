"""The board and its balls as batch-spawn groups: one group per shape, size and role."""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

from galton.analysis.board import BoardSpec, SurfaceSpec
from galton.analysis.board_geometry import Primitive, board_primitives
from galton.protocol import BodyGroup
from galton.protocol.mesh import box_mesh, half_extents, prism_mesh

BALL_TAG = "ball"
BOARD_TAG = "board"


def surface(spec: BoardSpec, engine: str, role: str) -> SurfaceSpec:
    """The friction and restitution a role gets on this engine: the board's material (None:
    the engine's default, as every role gets with ``materials = "engine"``)."""
    return spec.engine_contacts(engine).bodies.get(role, SurfaceSpec())


def board_groups(spec: BoardSpec, engine: str, offset_x: float = 0.0) -> list[BodyGroup]:
    """Every static solid of the board, grouped so that one spawn request builds it."""
    grouped: dict[tuple[Any, ...], list[Primitive]] = defaultdict(list)
    for prim in board_primitives(spec, offset_x):
        grouped[(prim.shape, prim.size, prim.role, prim.rgba)].append(prim)
    groups = []
    for (shape, size, role, rgba), prims in grouped.items():
        material = surface(spec, engine, role)
        groups.append(BodyGroup(**{
            "shape": shape, "size": size, **_mesh_of(spec, shape, size)},
            names=[p.name for p in prims],
            poses=np.array([p.pose for p in prims], dtype=float), static=True,
            friction=material.friction, restitution=material.restitution, rgba=rgba,
            tags=(BOARD_TAG, role)))
    return groups


PIN_SIDES = 16  # a mesh board's pins: 16-sided prisms (2.5 % less cross-section than a disc)


def _mesh_of(spec: BoardSpec, shape: str, size: tuple[float, ...]) -> dict[str, Any]:
    """A mesh board's part as a mesh group's fields (shape, size, vertices, faces); none
    for a board of primitives. A pin's prism has its corners on the pin's circle, as a
    mesh exported from a CAD model has."""
    if spec.parts != "mesh":
        return {}
    if shape == "cylinder":
        vertices, faces = prism_mesh(size[0], size[1], PIN_SIDES)
    elif shape == "box":
        vertices, faces = box_mesh((size[0], size[1], size[2]))
    else:
        raise ValueError(f"a mesh board has no mesh for a {shape}")
    return {"shape": "mesh", "size": half_extents(vertices), "vertices": vertices,
            "faces": faces}


def ball_group(spec: BoardSpec, engine: str, names: list[str],
               positions: np.ndarray) -> BodyGroup:
    """Balls at rest at these positions, with the board's ball material on this engine."""
    poses = np.zeros((len(names), 7))
    poses[:, :3] = positions
    poses[:, 6] = 1.0
    material = surface(spec, engine, BALL_TAG)
    inertia = None if spec.ball.inertia is None else (spec.ball.inertia,) * 3
    return BodyGroup(shape="sphere", size=(spec.ball.radius,), names=names, poses=poses,
                     mass=spec.ball.mass, inertia=inertia, friction=material.friction,
                     restitution=material.restitution, rgba=(0.9, 0.1, 0.1, 1.0),
                     tags=(BALL_TAG,))


def ball_names(count: int) -> list[str]:
    return [f"ball_{i:04d}" for i in range(count)]
