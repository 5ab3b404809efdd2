"""A PyBullet body's (or model link's) collision shapes in its link frame, as the
protocol's primitives (``get_shapes``).

Bullet reports each shape in the link's inertial frame (its centre of mass), with full
lengths where the protocol keeps half sizes. A mesh file's row is the box around the convex
hull PyBullet collides with (mesh_files.py), its triangles beside it; any other mesh (one
whose file cannot be read) is the link's own box (``getAABB``, world axes) turned into the
link frame: a box that holds the mesh, not the tightest one, with no triangles.
"""

from __future__ import annotations

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.base import Shape, ShapeMesh
from galton.daemon.engines.pybullet.mesh_files import HullCache

Pose = tuple[float, ...]


def link_shapes_and_meshes(bc: BulletClient, uid: int, link: int, hulls: HullCache | None
                           ) -> tuple[list[Shape], dict[int, ShapeMesh]]:
    """The link's shapes, and with ``hulls`` the triangles of its mesh rows by row index."""
    inertial = bc.getDynamicsInfo(uid, link)[3:5]
    found: list[Shape] = []
    meshes: dict[int, ShapeMesh] = {}
    for row in bc.getCollisionShapeData(uid, link):
        geometry, dimensions = int(row[2]), [float(v) for v in row[3]]
        position, orientation = bc.multiplyTransforms(*inertial, row[5], row[6])
        pose = (*position, *orientation)
        if geometry == pybullet.GEOM_SPHERE:
            found.append(("sphere", (dimensions[0],), pose))
        elif geometry == pybullet.GEOM_BOX:
            found.append(("box", tuple(d / 2 for d in dimensions), pose))
        elif geometry in (pybullet.GEOM_CYLINDER, pybullet.GEOM_CAPSULE):
            kind = "cylinder" if geometry == pybullet.GEOM_CYLINDER else "capsule"
            found.append((kind, (dimensions[1], dimensions[0] / 2), pose))
        elif geometry == pybullet.GEOM_PLANE:
            found.append(("plane", (0.0, 0.0), pose))
        else:
            hull = None
            if hulls is not None and geometry == pybullet.GEOM_MESH:
                hull = hulls.get(bytes(row[4]).decode(errors="replace"), tuple(dimensions))
            if hull is None:
                found.append(_mesh_box(bc, uid, link))
                continue
            centre, half, mesh = hull
            position, orientation = bc.multiplyTransforms(position, orientation,
                                                          centre.tolist(), (0, 0, 0, 1))
            meshes[len(found)] = mesh
            found.append(("mesh", tuple(float(v) for v in half),
                          (*(float(v) for v in position), *(float(v) for v in orientation))))
    return found, meshes


def _mesh_box(bc: BulletClient, uid: int, link: int) -> Shape:
    """The link's world box as a box in its own frame (axes turned, so it may grow)."""
    low, high = (np.asarray(v, dtype=float) for v in bc.getAABB(uid, link))
    if link < 0:
        position, orientation = bc.getBasePositionAndOrientation(uid)
        inertial = bc.getDynamicsInfo(uid, link)[3:5]
        inverse = bc.invertTransform(*inertial)
        position, orientation = bc.multiplyTransforms(position, orientation, *inverse)
    else:
        state = bc.getLinkState(uid, link, computeForwardKinematics=True)
        position, orientation = state[4], state[5]
    turn = np.asarray(bc.getMatrixFromQuaternion(orientation), dtype=float).reshape(3, 3)
    centre = turn.T @ ((low + high) / 2 - np.asarray(position, dtype=float))
    half = np.abs(turn.T) @ ((high - low) / 2)
    return ("mesh", tuple(float(v) for v in half),
            (*(float(v) for v in centre), 0.0, 0.0, 0.0, 1.0))
