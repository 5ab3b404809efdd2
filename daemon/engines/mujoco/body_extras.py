"""What a spawned MuJoCo body is made of beyond a primitive geom: a mesh group's asset
(its geoms collide with the mesh's convex hull) and a body's own inertia (an explicit
inertial). Neither kind of body is parked in the pool (``parked.key_of``)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines.geometry import DENSITY, group_volume
from galton.protocol import BodyGroup


def add_mesh(spec: mujoco.MjSpec, group: BodyGroup) -> str | None:
    """A mesh group's asset, named for it; its geoms collide with its convex hull."""
    if group.vertices is None or group.faces is None:
        return None
    serial = len(spec.meshes)
    while spec.mesh(f"{MESH_PREFIX}{serial}") is not None:
        serial += 1
    mesh = spec.add_mesh(name=f"{MESH_PREFIX}{serial}")
    mesh.uservert = np.asarray(group.vertices, dtype=float).reshape(-1).tolist()
    mesh.userface = np.asarray(group.faces, dtype=int).reshape(-1).tolist()
    return str(mesh.name)


MESH_PREFIX = "galton.mesh."


def inertial(group: BodyGroup, mass: float | None) -> dict[str, Any]:
    """A body's own inertia (spawn's ``inertia``) about its origin, with its mass: the
    group's, or the shape's volume at the default density."""
    if group.inertia is None:
        return {}
    if mass is None:
        mass = DENSITY * group_volume(group)
    return {"explicitinertial": True, "mass": mass, "inertia": list(group.inertia),
            "ipos": [0.0, 0.0, 0.0]}


