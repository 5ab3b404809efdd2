"""The board and its balls as batch-spawn groups: one group per shape, size and role."""

from __future__ import annotations

from collections import defaultdict
from typing import Any

import numpy as np

from galton.analysis.board import BoardSpec, SurfaceSpec
from galton.analysis.board_geometry import Primitive, board_primitives
from galton.protocol import BodyGroup

BALL_TAG = "ball"
BOARD_TAG = "board"


def surface(spec: BoardSpec, engine: str, role: str) -> SurfaceSpec:
    """The friction and restitution a role gets on this engine (None: engine default)."""
    contacts = spec.contacts.get(engine)
    if contacts is None:
        return SurfaceSpec()
    return contacts.bodies.get(role, SurfaceSpec())


def board_groups(spec: BoardSpec, engine: str, offset_x: float = 0.0) -> list[BodyGroup]:
    """Every static solid of the board, grouped so that one spawn request builds it."""
    grouped: dict[tuple[Any, ...], list[Primitive]] = defaultdict(list)
    for prim in board_primitives(spec, offset_x):
        grouped[(prim.shape, prim.size, prim.role, prim.rgba)].append(prim)
    groups = []
    for (shape, size, role, rgba), prims in grouped.items():
        material = surface(spec, engine, role)
        groups.append(BodyGroup(
            shape=shape, size=size, names=[p.name for p in prims],
            poses=np.array([p.pose for p in prims], dtype=float), static=True,
            friction=material.friction, restitution=material.restitution, rgba=rgba,
            tags=(BOARD_TAG, role)))
    return groups


def ball_group(spec: BoardSpec, engine: str, names: list[str],
               positions: np.ndarray) -> BodyGroup:
    """Balls at rest at these positions, with the board's ball material on this engine."""
    poses = np.zeros((len(names), 7))
    poses[:, :3] = positions
    poses[:, 6] = 1.0
    material = surface(spec, engine, BALL_TAG)
    return BodyGroup(shape="sphere", size=(spec.ball.radius,), names=names, poses=poses,
                     mass=spec.ball.mass, friction=material.friction,
                     restitution=material.restitution, rgba=(0.9, 0.1, 0.1, 1.0),
                     tags=(BALL_TAG,))


def ball_names(count: int) -> list[str]:
    return [f"ball_{i:04d}" for i in range(count)]
