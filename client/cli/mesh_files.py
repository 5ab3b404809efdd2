"""Triangle meshes for ``galton-client spawn mesh --mesh FILE``: a Wavefront OBJ's vertices
(``v x y z``) and faces (``f a b c ...``, 1-based or negative indices, ``a/t/n`` forms),
polygons split into fans of triangles. Everything else in the file is skipped."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from galton.protocol import InvalidArgumentError
from galton.protocol.vocabulary import MAX_MESH_VERTICES

MAX_OBJ_BYTES = 64 * 1024 * 1024


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) vertices and (m, 3) 0-based triangles; InvalidArgumentError naming the line
    for what is not an OBJ this reads. The daemon checks the mesh itself (docs/protocol.md)."""
    if path.stat().st_size > MAX_OBJ_BYTES:
        raise InvalidArgumentError(f"{path}: larger than {MAX_OBJ_BYTES} bytes")
    vertices: list[list[float]] = []
    faces: list[list[int]] = []
    for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        words = line.split()
        try:
            if words[:1] == ["v"]:
                vertices.append([float(w) for w in words[1:4]])
                if len(vertices[-1]) != 3 or len(vertices) > MAX_MESH_VERTICES:
                    raise ValueError("a vertex takes x y z; at most "
                                     f"{MAX_MESH_VERTICES} vertices")
            elif words[:1] == ["f"]:
                corners = [_index(w, len(vertices)) for w in words[1:]]
                faces += [[corners[0], corners[k], corners[k + 1]]
                          for k in range(1, len(corners) - 1)]
        except ValueError as error:
            raise InvalidArgumentError(f"{path} line {number}: {error}") from None
    if not vertices or not faces:
        raise InvalidArgumentError(f"{path} holds no vertices or no faces ('v', 'f' lines)")
    return np.array(vertices, dtype=float), np.array(faces, dtype=np.int64)


def _index(word: str, count: int) -> int:
    """An OBJ face corner's vertex as a 0-based index (``-1`` is the last vertex so far)."""
    index = int(word.split("/")[0])
    if index == 0 or abs(index) > count:
        raise ValueError(f"vertex index {index} is not among the {count} read so far")
    return index - 1 if index > 0 else count + index
