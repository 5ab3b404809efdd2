"""Triangle meshes as DART ``MeshShape``s, which dartpy can only make by loading a file.

dartpy 6.20 binds ``MeshShape(scale, aiScene)`` but no way to make an Assimp ``aiScene``
from Python, nor ``MeshShape::loadMesh``; its model loaders do load meshes (through
Assimp), so the engine writes the mesh as a binary STL in a temporary folder, loads a
one-link URDF naming it with ``DartLoader`` and keeps the link's shape: a ``MeshShape``
holding its own ``aiScene``, the file no longer needed. gz-physics does in effect the same
(dartsim/src/CustomMeshShape.cc turns a loaded gz-common mesh into an aiScene). Assimp
keeps vertices in float32 (``ai_real``), so a mesh's vertices are rounded to float32 as
any route into DART rounds them; DART's ODE collision detector collides the shape as an
ODE trimesh.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import dartpy as dart
import numpy as np

_STL_TRIANGLE = np.dtype([("normal", "<f4", (3,)), ("corners", "<f4", (3, 3)),
                          ("attributes", "<u2")])


def stl_bytes(vertices: np.ndarray, faces: np.ndarray) -> bytes:
    """The mesh as a binary STL (Assimp reads no ASCII STL written this way: it failed)."""
    triangles = np.zeros(len(faces), dtype=_STL_TRIANGLE)
    triangles["corners"] = vertices[faces]
    count = len(faces).to_bytes(4, "little")
    return bytes(80) + count + triangles.tobytes()


def mesh_shape(vertices: np.ndarray, faces: np.ndarray) -> Any:
    """A DART ``MeshShape`` of these triangles (the body's frame, metres)."""
    with tempfile.TemporaryDirectory(prefix="galton-dart-mesh-") as folder:
        path = Path(folder) / "mesh.stl"
        path.write_bytes(stl_bytes(np.asarray(vertices, dtype=float),
                                   np.asarray(faces, dtype=np.int64)))
        urdf = (f'<robot name="mesh"><link name="mesh"><collision><geometry>'
                f'<mesh filename="{path.as_uri()}"/></geometry></collision></link></robot>')
        skeleton = dart.utils.DartLoader().parseSkeletonString(
            urdf, dart.common.Uri(Path(folder).as_uri() + "/"))
        node = None if skeleton is None else skeleton.getBodyNode(0)
        if node is None or node.getNumShapeNodes() != 1:
            raise RuntimeError("dartpy could not load the mesh it wrote")  # never seen
        return node.getShapeNode(0).getShape()
