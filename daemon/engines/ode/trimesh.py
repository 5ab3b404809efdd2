"""Triangle meshes as ODE trimesh geoms, as Webots collides its meshes (docs/ENGINES.md).

ODE does not copy a mesh: ``dGeomTriMeshDataBuildDouble`` keeps pointers to the vertex and
index arrays, so each ``TriMesh`` holds both (C-contiguous float64 rows of 3, uint32 rows
of 3: libode's ``dTriIndex``) for as long as its geom lives, and frees ODE's data after the
geom (``release``). A moving mesh's mass and inertia are ODE's own integration over its
triangles (``dMassSetTrimeshTotal``), about its centre of mass.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass

import numpy as np

from galton.daemon.engines.ode.native import LIB, TRIMESH, Mass

_VERTEX_STRIDE = 3 * ctypes.sizeof(ctypes.c_double)
_TRIANGLE_STRIDE = 3 * ctypes.sizeof(ctypes.c_uint32)


@dataclass
class TriMesh:
    """A mesh's arrays, kept alive beside the ODE trimesh data that points into them."""

    vertices: np.ndarray  # (n, 3) float64, C order: ODE reads it in place
    indices: np.ndarray  # (m, 3) uint32, C order
    data: int = 0  # dTriMeshDataID; 0 once released

    @classmethod
    def build(cls, vertices: np.ndarray, faces: np.ndarray) -> TriMesh:
        mesh = cls(np.ascontiguousarray(vertices, dtype=np.float64),
                   np.ascontiguousarray(faces, dtype=np.uint32))
        mesh.data = int(LIB.dGeomTriMeshDataCreate())
        LIB.dGeomTriMeshDataBuildDouble(
            mesh.data, mesh.vertices.ctypes.data, _VERTEX_STRIDE, len(mesh.vertices),
            mesh.indices.ctypes.data, mesh.indices.size, _TRIANGLE_STRIDE)
        return mesh

    def geom(self, space: int) -> int:
        """A new trimesh geom over this mesh, in ``space``."""
        geom = int(LIB.dCreateTriMesh(space, self.data, None, None, None))
        if LIB.dGeomGetClass(geom) != TRIMESH:  # never: libode's class numbers are fixed
            raise RuntimeError("libode made no trimesh")
        return geom

    def release(self) -> None:
        """Free ODE's data (after every geom over it is destroyed)."""
        if self.data:
            LIB.dGeomTriMeshDataDestroy(self.data)
            self.data = 0


def centred_mass(geom: int, vertices: np.ndarray, faces: np.ndarray, total: float
                 ) -> tuple[Mass, np.ndarray] | None:
    """ODE's mass of the solid mesh of that total (a geom at its body's origin, unturned),
    about its centre of mass, and that centre in the body's frame; None where the mesh
    encloses no volume (open or inward-wound: ODE's integral would be meaningless)."""
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    if float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) <= 0:
        return None
    mass = Mass()
    LIB.dMassSetTrimeshTotal(ctypes.addressof(mass), total, geom)
    # libode 0.16 gives the inertia about the centre already, and the centre in ``c``.
    centre = np.array(mass.c[:3], dtype=float)
    inertia = np.array(mass.I[:12], dtype=float).reshape(3, 4)[:, :3]
    if not (np.isfinite(centre).all() and np.isfinite(inertia).all()
            and np.linalg.eigvalsh(inertia).min() > 0):
        return None
    mass.c[0] = mass.c[1] = mass.c[2] = 0.0
    return mass, centre
