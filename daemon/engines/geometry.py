"""Solid geometry every engine shares: a spawned body's volume and its default mass, and
the inertia of a uniform primitive. One formula each, so that four engines give a body
with no mass the same mass (docs/protocol.md, "spawn")."""

from __future__ import annotations

import math

from galton.protocol import BodyGroup, InvalidArgumentError
from galton.protocol import mesh as mesh_wire
from galton.protocol.vocabulary import BODY_SHAPES

DENSITY = 1000.0  # kg/m³: the protocol's mass for a dynamic body spawned with mass None


def check_group(group: BodyGroup) -> None:
    """Refuse a shape the protocol does not know, and a plane that would move."""
    if group.shape not in BODY_SHAPES:
        raise InvalidArgumentError(f"unknown shape {group.shape!r}")
    if group.shape == "plane" and not group.static:
        raise InvalidArgumentError("a plane must be static")


def volume(shape: str, size: tuple[float, ...]) -> float:
    """Volume (m³) of a solid primitive from its half sizes (docs/protocol.md, SIZE_LAYOUT);
    a plane has none (only static bodies may be planes)."""
    if shape == "sphere":
        return 4 / 3 * math.pi * size[0] ** 3
    if shape == "box":
        return 8 * size[0] * size[1] * size[2]
    if shape not in ("cylinder", "capsule"):
        raise ValueError(f"a {shape} has no volume: only static bodies may be {shape}s")
    radius, half = size
    cylinder = math.pi * radius**2 * 2 * half
    return cylinder + (4 / 3 * math.pi * radius**3 if shape == "capsule" else 0.0)


def group_volume(group: BodyGroup) -> float:
    """A spawn group's body volume (m³): its mesh's where it has one, else its shape's."""
    if group.vertices is not None and group.faces is not None:
        return mesh_wire.volume(group.vertices, group.faces)
    return volume(group.shape, tuple(float(s) for s in group.size))


def default_mass(group: BodyGroup) -> float:
    """The mass (kg) of one of the group's bodies: its own, or DENSITY times its volume."""
    return float(group.mass) if group.mass is not None else DENSITY * group_volume(group)


def unit_inertia(shape: str, size: tuple[float, ...]) -> tuple[float, float, float]:
    """Principal moments of inertia per kilogram (uniform density), about the body axes
    (a cylinder's and a capsule's along z)."""
    if shape == "sphere":
        moment = 0.4 * size[0] ** 2
        return (moment, moment, moment)
    if shape == "box":
        x2, y2, z2 = (h * h for h in size)
        return ((y2 + z2) / 3, (x2 + z2) / 3, (x2 + y2) / 3)
    radius, half = size
    r2, length = radius * radius, 2 * half
    if shape == "cylinder":
        side = r2 / 4 + length * length / 12
        return (side, side, r2 / 2)
    if shape == "capsule":
        # Cylinder plus two hemispheres, weighted by volume (the standard capsule formula).
        cyl, caps = math.pi * r2 * length, 4 / 3 * math.pi * r2 * radius
        side = (cyl * (length * length / 12 + r2 / 4)
                + caps * (0.4 * r2 + length * length / 4 + 3 * length * radius / 8))
        axial = cyl * r2 / 2 + caps * 0.4 * r2
        total = cyl + caps
        return (side / total, side / total, axial / total)
    raise ValueError(f"a {shape} has no inertia: only static bodies may be {shape}s")
