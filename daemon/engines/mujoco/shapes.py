"""What a spawned MuJoCo body is made of beyond a primitive geom: a mesh group's asset
(its geoms collide with the mesh's convex hull) and a body's own inertia (an explicit
inertial). Neither kind of body is parked in the pool (``pool.key_of``)."""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco import spec as ms
from galton.protocol import BodyGroup
from galton.protocol import mesh as mesh_wire


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
        mass = ms.DENSITY * shape_volume(group)
    return {"explicitinertial": True, "mass": mass, "inertia": list(group.inertia),
            "ipos": [0.0, 0.0, 0.0]}


def shape_volume(group: BodyGroup) -> float:
    """A spawned shape's volume (m³), from its half sizes or its mesh."""
    size = group.size
    if group.vertices is not None and group.faces is not None:
        return mesh_wire.volume(group.vertices, group.faces)
    if group.shape == "sphere":
        return 4 / 3 * np.pi * size[0] ** 3
    if group.shape == "cylinder":
        return 2 * np.pi * size[0] ** 2 * size[1]
    if group.shape == "capsule":
        return np.pi * size[0] ** 2 * (2 * size[1] + 4 / 3 * size[0])
    return 8 * size[0] * size[1] * size[2]
