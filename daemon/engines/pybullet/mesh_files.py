"""The triangles PyBullet collides a model's mesh link with (``get_shapes``).

PyBullet's URDF importer makes a mesh file's collision shape the convex hull of all its
vertices (scaled), unless the link is marked concave; getCollisionShapeData names the file
and scale but gives no triangles, so the file is read here (trimesh, local files only) and
its hull taken (scipy), once per file and scale. The hull is centred on its own box, so
that a row's pose and half sizes are the box around it. trimesh and scipy are imported
only when a model's mesh is first asked for: a robot's daemon without them (the ``view``
extra brings them) tells such a link as its box, flagged, as before.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.engines.base import ShapeMesh

# (file, scale) -> the hull's centre in the mesh file's frame, its half sizes, its mesh
# (vertices about that centre); None where the file cannot be read as triangles.
HullEntry = tuple[np.ndarray, np.ndarray, ShapeMesh] | None


class HullCache:
    """Each mesh file's hull, read once and shared by every link and body that uses it."""

    def __init__(self) -> None:
        self._hulls: dict[tuple[str, tuple[float, ...]], HullEntry] = {}

    def get(self, path: str, scale: tuple[float, ...]) -> HullEntry:
        key = (path, tuple(float(s) for s in scale))
        if key not in self._hulls:
            self._hulls[key] = _read_hull(path, np.asarray(key[1], dtype=float))
        return self._hulls[key]


def _read_hull(path: str, scale: np.ndarray) -> HullEntry:
    try:
        import trimesh
        from scipy.spatial import ConvexHull, QhullError
    except ImportError:
        return None  # the view's extra is not installed: told as its box
    try:
        loaded: Any = trimesh.load(path, force="mesh", process=False)  # a Trimesh
        points = np.asarray(loaded.vertices, dtype=float) * scale
        hull = ConvexHull(points)
    except (OSError, ValueError, IndexError, QhullError):
        return None  # not a file trimesh reads, or flat: told as its box
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2
    used, faces = np.unique(hull.simplices, return_inverse=True)
    vertices = np.ascontiguousarray(points[used] - centre)
    faces = faces.reshape(-1, 3).astype(np.int64)
    return centre, (high - low) / 2, (vertices, _outward(vertices, faces))


def _outward(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Faces wound counter-clockwise seen from outside (Qhull leaves them either way)."""
    corners = vertices[faces]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    outward = corners.mean(axis=1) - vertices.mean(axis=0)
    flip = np.einsum("ij,ij->i", normals, outward) < 0
    faces = faces.copy()
    faces[flip] = faces[flip][:, ::-1]
    return faces
