"""The visual meshes the PyBullet engine gives its spawned bodies (PyBullet renders only in
images, through TinyRenderer): a box or a plane as its faces, a sphere, cylinder or capsule
as a solid of revolution with segments enough that a depth image is within MESH_TOLERANCE
of the true surface.
"""

from __future__ import annotations

import functools
import itertools
import math

Mesh = tuple[list[list[float]], list[int]]  # vertices, triangle indices
# Segments round a circle of the visual meshes of spheres, cylinders and capsules: enough
# that no chord lies more than MESH_TOLERANCE inside the true surface (a depth image shows
# the mesh), a multiple of 4 between these bounds (a Galton board's small balls keep 8).
MESH_TOLERANCE = 2e-3  # m
MIN_SEGMENTS, MAX_SEGMENTS = 8, 64


def segments(radius: float) -> int:
    """How many segments round a circle of this radius keep within MESH_TOLERANCE."""
    if radius <= MESH_TOLERANCE:
        return MIN_SEGMENTS
    least = math.ceil(math.pi / math.acos(1.0 - MESH_TOLERANCE / radius))
    return min(MAX_SEGMENTS, max(MIN_SEGMENTS, 4 * math.ceil(least / 4)))


def _lathe(profile: list[tuple[float, float]], count: int) -> Mesh:
    """A solid of revolution about z from (radius, z) points, poles where the radius is 0,
    ``count`` segments round."""
    angles = [2 * math.pi * k / count for k in range(count)]
    vertices: list[list[float]] = []
    rings: list[list[int]] = []
    for radius, z in profile:
        start = len(vertices)
        if radius == 0:
            vertices.append([0.0, 0.0, z])
            rings.append([start] * count)
        else:
            vertices.extend([radius * math.cos(a), radius * math.sin(a), z] for a in angles)
            rings.append(list(range(start, start + count)))
    indices: list[int] = []
    for low, high in itertools.pairwise(rings):
        for k in range(count):
            j = (k + 1) % count
            for tri in ((low[k], low[j], high[j]), (low[k], high[j], high[k])):
                if len(set(tri)) == 3:
                    indices.extend(tri)
    return vertices, indices


def _arc(radius: float, centre_z: float, first: float, last: float,
         steps: int) -> list[tuple[float, float]]:
    """(radius, z) profile of a circle of ``radius`` about ``centre_z``, from polar angle
    ``first`` to ``last`` (0 is the bottom pole, pi the top one)."""
    points = []
    for k in range(steps + 1):
        angle = first + (last - first) * k / steps
        ring = radius * math.sin(angle)
        points.append((ring if ring > 1e-9 * radius else 0.0, centre_z - radius * math.cos(angle)))
    return points


def visual_mesh(shape: str, size: tuple[float, ...]) -> Mesh:
    """A triangle mesh of the shape, for looks (PyBullet renders only in images), within
    MESH_TOLERANCE of its surface."""
    if shape in ("box", "plane"):
        hx, hy, hz = (*size[:2], 0.0) if shape == "plane" else size
        vertices = [[sx * hx, sy * hy, sz * hz] for sz in (-1, 1) for sy in (-1, 1)
                    for sx in (-1, 1)]
        faces = [0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4,
                 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5]
        return vertices, faces if shape == "box" else faces[6:12]
    count = segments(size[0])
    quarter = count // 4
    if shape == "sphere":
        return _lathe(_arc(size[0], 0.0, 0.0, math.pi, 2 * quarter), count)
    radius, half = size
    if shape == "cylinder":
        return _lathe([(0.0, -half), (radius, -half), (radius, half), (0.0, half)], count)
    if shape == "capsule":
        return _lathe(_arc(radius, -half, 0.0, math.pi / 2, quarter)
                      + _arc(radius, half, math.pi / 2, math.pi, quarter), count)
    raise ValueError(f"unknown shape {shape!r}")


@functools.cache
def shared_mesh(shape: str, size: tuple[float, ...]) -> Mesh:
    """``visual_mesh``, made once per process and handed to every world that needs it.

    PyBullet's createVisualShape keeps a reference to the vertex list, each vertex and the
    index list it is given and never lets go, so a mesh built afresh after each
    resetSimulation leaked about 5.7 kB (one sphere's mesh) per world cleared. Reused
    lists only gain references: what stays is one mesh per shape and size ever shown.
    """
    return visual_mesh(shape, size)
