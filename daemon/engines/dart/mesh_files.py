"""The triangles of a loaded model's mesh links on DART (``get_shapes``).

DART collides a URDF mesh as its triangles (its ODE collision detector makes an ODE
trimesh of the Assimp scene), but dartpy 6.20 gives no access to that scene: only the
mesh's path and scale. The file is read here with trimesh (local files only), scaled,
once per file and scale; a file it cannot read leaves the row as its box, and so does a
daemon without trimesh (imported when a model's mesh is first asked for).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.engines.base import ShapeMesh


class MeshFiles:
    """Each mesh file's triangles, read once and shared by every link that uses it."""

    def __init__(self) -> None:
        self._meshes: dict[tuple[str, tuple[float, ...]], ShapeMesh | None] = {}

    def get(self, path: str, scale: tuple[float, ...]) -> ShapeMesh | None:
        key = (path, tuple(float(s) for s in scale))
        if key not in self._meshes:
            self._meshes[key] = _read(path, np.asarray(key[1], dtype=float))
        return self._meshes[key]


def _read(path: str, scale: np.ndarray) -> ShapeMesh | None:
    if not path:
        return None
    try:
        import trimesh
    except ImportError:
        return None  # told as its box
    try:
        loaded: Any = trimesh.load(path, force="mesh", process=False)  # a Trimesh
    except (OSError, ValueError, IndexError):
        return None
    vertices = np.asarray(loaded.vertices, dtype=float) * scale
    faces = np.asarray(loaded.faces, dtype=np.int64).reshape(-1, 3)
    if len(vertices) == 0 or len(faces) == 0:
        return None
    return np.ascontiguousarray(vertices), faces
