"""A spawn group's triangle mesh (shape ``mesh``): vertices as packed float64 rows of 3 and
faces as packed uint32 rows of 3 (indices into the vertices), in the body's frame.

Every check lives here so that a refused mesh is refused before any engine sees it: widths,
counts against MAX_MESH_VERTICES / MAX_MESH_FACES, non-finite numbers, indices out of
range, faces that repeat a vertex, and meshes that are flat or have no area (no engine can
make a hull or a volume of them).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.protocol.arrays import pack_f64, unpack_f64
from galton.protocol.errors import InvalidArgumentError
from galton.protocol.vocabulary import MAX_MESH_FACES, MAX_MESH_VERTICES

_INDEX_DTYPE = np.dtype("<u4")
MIN_EXTENT = 1e-6  # m: a mesh thinner than this along an axis is flat


def pack_faces(faces: np.ndarray) -> bytes:
    """Triangles as little-endian uint32 rows of 3."""
    return np.ascontiguousarray(faces, dtype=_INDEX_DTYPE).tobytes()


def pack_vertices(vertices: np.ndarray) -> bytes:
    return pack_f64(np.asarray(vertices, dtype=float).reshape(-1, 3))


def decode_vertices(data: Any, where: str) -> np.ndarray:
    vertices = unpack_f64(data, 3, where)
    if not 4 <= len(vertices) <= MAX_MESH_VERTICES:
        raise InvalidArgumentError(f"{where} holds {len(vertices)} vertices; a mesh needs 4 "
                                   f"to {MAX_MESH_VERTICES}")
    if not np.isfinite(vertices).all():
        bad = int(np.argwhere(~np.isfinite(vertices))[0][0])
        raise InvalidArgumentError(f"{where} row {bad} holds NaN or infinity: "
                                   f"{vertices[bad].tolist()}")
    if (np.abs(vertices) > 1e4).any():
        raise InvalidArgumentError(f"{where} holds a vertex beyond 1e4 m of the body's origin")
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    if (extent < MIN_EXTENT).any():
        raise InvalidArgumentError(f"{where} is flat (extent {extent.tolist()} m): a mesh "
                                   f"must span at least {MIN_EXTENT} m along x, y and z")
    return vertices


def decode_faces(data: Any, count: int, where: str) -> np.ndarray:
    """(m, 3) int64 indices below ``count``, each face three distinct vertices, some area."""
    if not isinstance(data, bytes | bytearray | memoryview):
        raise InvalidArgumentError(
            f"{where} must be msgpack bin of little-endian uint32, got {type(data).__name__}")
    if len(data) % 12:
        raise InvalidArgumentError(f"{where} holds {len(data)} bytes, not a whole number of "
                                   "triangles (3 uint32, 12 bytes each)")
    faces = np.frombuffer(data, dtype=_INDEX_DTYPE).reshape(-1, 3).astype(np.int64)
    if not 1 <= len(faces) <= MAX_MESH_FACES:
        raise InvalidArgumentError(f"{where} holds {len(faces)} triangles; a mesh needs 1 to "
                                   f"{MAX_MESH_FACES}")
    if (faces >= count).any():
        bad = int(np.argwhere(faces >= count)[0][0])
        raise InvalidArgumentError(f"{where} row {bad} {faces[bad].tolist()} names a vertex "
                                   f"beyond the {count} given (indices 0..{count - 1})")
    repeated = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | \
        (faces[:, 0] == faces[:, 2])
    if repeated.any():
        bad = int(np.argmax(repeated))
        raise InvalidArgumentError(f"{where} row {bad} {faces[bad].tolist()} repeats a vertex: "
                                   "a triangle needs three distinct ones")
    return faces


def check_area(vertices: np.ndarray, faces: np.ndarray, where: str) -> None:
    """Refuse a mesh whose triangles have no area at all (every one degenerate)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    areas = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 2
    if float(areas.sum()) <= MIN_EXTENT ** 2:
        raise InvalidArgumentError(f"{where}: the mesh's triangles have no area")


def half_extents(vertices: np.ndarray) -> tuple[float, float, float]:
    """Half the bounding box's sides, about the body's origin (a mesh's ``size``)."""
    reach = np.abs(vertices).max(axis=0)
    return (float(reach[0]), float(reach[1]), float(reach[2]))


def box_mesh(half: tuple[float, float, float] | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A box about the origin as 8 vertices and 12 outward-facing triangles."""
    hx, hy, hz = (float(v) for v in half)
    corners = np.array([[sx * hx, sy * hy, sz * hz] for sz in (-1, 1) for sy in (-1, 1)
                        for sx in (-1, 1)])
    return corners, _BOX_FACES.copy()


def prism_mesh(radius: float, half_length: float, sides: int) -> tuple[np.ndarray, np.ndarray]:
    """A right prism with a regular ``sides``-gon section about the z axis (a pin)."""
    angles = np.arange(sides) * 2 * np.pi / sides
    ring = np.column_stack([radius * np.cos(angles), radius * np.sin(angles)])
    vertices = np.vstack([np.column_stack([ring, np.full(sides, -half_length)]),
                          np.column_stack([ring, np.full(sides, half_length)])])
    faces = []
    for i in range(sides):
        j = (i + 1) % sides
        faces += [[i, j, sides + j], [i, sides + j, sides + i]]
    for i in range(1, sides - 1):
        faces += [[0, i + 1, i], [sides, sides + i, sides + i + 1]]
    return vertices, np.array(faces, dtype=np.int64)


_BOX_FACES = np.array([[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
                       [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]],
                      dtype=np.int64)


def volume(vertices: np.ndarray, faces: np.ndarray) -> float:
    """The enclosed volume (m³) of a closed, outward-wound mesh; its bounding box's where
    the winding or closure gives none (a body's default mass is its density times this)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    signed = float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6
    if signed > 0:
        return signed
    return _box_volume(vertices)


def _box_volume(vertices: np.ndarray) -> float:
    """The bounding box's volume: an upper bound where the mesh encloses none."""
    extent = vertices.max(axis=0) - vertices.min(axis=0)
    return float(np.prod(extent))
