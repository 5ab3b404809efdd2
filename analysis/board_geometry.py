"""The board as static primitives (boxes and cylinders only), and distances to them.

MuJoCo collides a mesh as its convex hull and both engines collide primitives far faster
than meshes, so the board is built from primitives: ``board_primitives(spec)`` returns one
``Primitive`` per solid, which a client turns into a batch spawn. Sizes are half sizes, as
on the wire: box (hx, hy, hz); cylinder (radius, half_length) along its local z, so a pin
along y carries a 90-degree rotation about x. Poses are x y z qx qy qz qw (scalar last).

``signed_distance`` (negative inside) serves the release (balls start clear of every
solid) and the scoring (a ball whose centre is inside a solid tunnelled into it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.analysis.board_layout import (
    board_top,
    cavity_faces,
    divider_positions,
    divider_top,
    pin_centres,
)

if TYPE_CHECKING:
    from galton.analysis.board import BoardSpec

SHAPES = ("box", "cylinder", "sphere", "capsule", "plane")
ROLES = ("pin", "funnel", "divider", "wall", "floor", "glass")
IDENTITY = (0.0, 0.0, 0.0, 1.0)
# A cylinder's local z turned onto world y: a quarter turn about x.
ALONG_Y = (math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4))
ROLE_RGBA: dict[str, tuple[float, float, float, float]] = {
    "pin": (0.28, 0.30, 0.33, 1.0),
    "funnel": (0.80, 0.36, 0.19, 1.0),
    "divider": (0.80, 0.36, 0.19, 1.0),
    "wall": (0.45, 0.55, 0.80, 1.0),
    "floor": (0.50, 0.50, 0.50, 1.0),
    "glass": (0.80, 0.90, 1.00, 0.15),
}


@dataclass(frozen=True)
class Primitive:
    """One static solid of the board; ``size`` holds half sizes, ``pose`` x y z qx qy qz qw."""

    name: str
    shape: str
    size: tuple[float, ...]
    pose: tuple[float, ...]
    role: str
    static: bool = True
    rgba: tuple[float, float, float, float] | None = None

    @property
    def position(self) -> np.ndarray:
        return np.array(self.pose[:3])

    @property
    def rotation(self) -> np.ndarray:
        """The 3x3 matrix taking local vectors to world vectors."""
        return quat_to_matrix(self.pose[3:])

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "shape": self.shape, "size": list(self.size),
                "pose": list(self.pose), "role": self.role, "static": self.static,
                "rgba": None if self.rgba is None else list(self.rgba)}


def quat_about_y(angle: float) -> tuple[float, float, float, float]:
    """Rotation by ``angle`` radians about +y, as (qx, qy, qz, qw)."""
    return (0.0, math.sin(angle / 2), 0.0, math.cos(angle / 2))


def quat_to_matrix(q: tuple[float, ...] | np.ndarray) -> np.ndarray:
    x, y, z, w = np.asarray(q, dtype=float) / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def signed_distance(prim: Primitive, points: np.ndarray) -> np.ndarray:
    """Distance from each point (n, 3) to the solid's surface; negative inside."""
    local = (np.atleast_2d(points) - prim.position) @ prim.rotation
    size = np.asarray(prim.size)
    distance: np.ndarray
    if prim.shape == "box":
        distance = _box_sdf(local, size)
    elif prim.shape == "cylinder":
        radial = np.linalg.norm(local[:, :2], axis=1)
        distance = _box_sdf(np.stack([radial, local[:, 2]], axis=1), size)
    elif prim.shape == "sphere":
        distance = np.linalg.norm(local, axis=1) - size[0]
    elif prim.shape == "capsule":
        axial = np.clip(local[:, 2], -size[1], size[1])
        distance = np.linalg.norm(local - np.outer(axial, [0, 0, 1]), axis=1) - size[0]
    else:
        distance = local[:, 2]  # plane: its local +z is the outward normal
    return distance


def _box_sdf(local: np.ndarray, half: np.ndarray) -> np.ndarray:
    q = np.abs(local) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    distance: np.ndarray = outside + np.minimum(q.max(axis=1), 0.0)
    return distance


def board_primitives(spec: BoardSpec, offset_x: float = 0.0) -> list[Primitive]:
    """Every static solid of the board, shifted by ``offset_x`` along x.

    Order: floor, side walls, back wall, front glass, funnel walls, dividers, pins.
    """
    parts = _shell(spec) + _funnel(spec) + _dividers(spec) + _pins(spec)
    return [_placed(p, offset_x) for p in parts]


def _placed(prim: Primitive, dx: float) -> Primitive:
    """The primitive shifted by dx along x, coloured by its role."""
    x, y, z, *quat = prim.pose
    return Primitive(prim.name, prim.shape, prim.size, (x + dx, y, z, *quat), prim.role,
                     prim.static, ROLE_RGBA[prim.role])


def _box(name: str, role: str, lo: tuple[float, float, float],
         hi: tuple[float, float, float]) -> Primitive:
    """An axis-aligned box from its lower and upper corners."""
    centre = tuple((a + b) / 2 for a, b in zip(lo, hi, strict=True))
    half = tuple((b - a) / 2 for a, b in zip(lo, hi, strict=True))
    return Primitive(name, "box", half, (*centre, *IDENTITY), role)


def _shell(spec: BoardSpec) -> list[Primitive]:
    """Floor, side walls, back wall and front glass: a closed box around the cavity.

    The glass and back wall fit between the side walls; the side walls and the floor span
    the glass and back wall too, so solids touch along faces and nothing overlaps.
    """
    front, back = cavity_faces(spec)
    y_lo, y_hi = front - spec.cavity.glass_thickness, back + spec.cavity.back_thickness
    x_in, x_out = spec.walls.inner_x, spec.walls.inner_x + spec.walls.thickness
    z0, top = spec.floor.z, board_top(spec)
    return [
        _box("floor", "floor", (-x_out, y_lo, z0 - spec.floor.thickness), (x_out, y_hi, z0)),
        _box("wall_left", "wall", (-x_out, y_lo, z0), (-x_in, y_hi, top)),
        _box("wall_right", "wall", (x_in, y_lo, z0), (x_out, y_hi, top)),
        _box("back_wall", "wall", (-x_in, back, z0), (x_in, y_hi, top)),
        _box("front_glass", "glass", (-x_in, y_lo, z0), (x_in, front, top)),
    ]


def _funnel(spec: BoardSpec) -> list[Primitive]:
    """Two boxes whose upper faces run from the tips at +-opening / 2 up to +-outer_x.

    Each box's top face contains that segment; the box hangs ``thickness`` below it, normal
    to the slope. Its outer end reaches into the side wall (the only overlap on the board),
    so no ball can lodge between funnel and wall.
    """
    f = spec.funnel
    angle = math.radians(f.angle_deg)
    length = (f.outer_x - f.opening / 2) / math.cos(angle)
    half = (length / 2, spec.cavity.depth / 2, f.thickness / 2)
    walls = []
    for side, name in ((1.0, "funnel_right"), (-1.0, "funnel_left")):
        along = np.array([side * math.cos(angle), math.sin(angle)])  # up the slope, outward
        normal = np.array([-side * math.sin(angle), math.cos(angle)])  # out of the top face
        tip = np.array([side * f.opening / 2, f.tip_z])
        cx, cz = (float(v) for v in tip + along * length / 2 - normal * f.thickness / 2)
        pose = (cx, spec.cavity.centre_y, cz, *quat_about_y(-side * angle))
        walls.append(Primitive(name, "box", half, pose, "funnel"))
    return walls


def _dividers(spec: BoardSpec) -> list[Primitive]:
    half_t = spec.dividers.thickness / 2
    front, back = cavity_faces(spec)
    return [_box(f"divider_{i:02d}", "divider", (x - half_t, front, spec.floor.z),
                 (x + half_t, back, divider_top(spec)))
            for i, x in enumerate(divider_positions(spec))]


def _pins(spec: BoardSpec) -> list[Primitive]:
    size = (spec.pins.radius, spec.pins.length / 2)
    y = spec.cavity.centre_y
    return [Primitive(f"pin_r{row:02d}_c{col:02d}", "cylinder", size, (x, y, z, *ALONG_Y), "pin")
            for row, col, x, z in pin_centres(spec)]
