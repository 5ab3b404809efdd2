"""The pure parts of spawning into PyBullet: a group's checks, mass, dynamics and records.

The engine's ``_spawn_group`` makes the bodies (one createMultiBody call for a group, all
turned like its first body) and hands them these values; a rebuild makes them again from
the records, through the same calls (rebuild).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.engines.geometry import DENSITY, unit_inertia, volume
from galton.daemon.engines.pybullet import rebuild
from galton.daemon.engines.pybullet.bodies import as_rgba
from galton.daemon.engines.pybullet.params import default_keys
from galton.daemon.engines.pybullet.rebuild import Body
from galton.protocol import BodyGroup
from galton.protocol import mesh as mesh_wire


def first_redo(poses: list[list[float]]) -> rebuild.Redo:
    """How a group is first made: every body turned like the first, then each one that
    differs turned to its own."""
    turn = tuple(poses[0][3:])
    return rebuild.Redo(turn, [any(pose[3:] != poses[0][3:] for pose in poses)] * len(poses))


def group_mass(group: BodyGroup, size: tuple[float, ...]) -> float:
    """Each body's mass: 0 when static, else the given one or the protocol's
    default density's."""
    if group.static:
        return 0.0
    if group.mass is not None:
        return group.mass
    if group.vertices is not None and group.faces is not None:
        return DENSITY * mesh_wire.volume(group.vertices, group.faces)
    return DENSITY * volume(group.shape, size)


def group_unit_inertia(group: BodyGroup, size: tuple[float, ...], mass: float
                       ) -> tuple[float, float, float] | None:
    """Principal moments per kilogram: the spawn's own inertia, else the shape's (a mesh's
    is its bounding box's, as Bullet's own estimate); None for a static body."""
    if group.static:
        return None
    if group.inertia is not None:
        ixx, iyy, izz = (i / mass for i in group.inertia)
        return (ixx, iyy, izz)
    return unit_inertia("box" if group.shape == "mesh" else group.shape, size)


def dynamics(group: BodyGroup, size: tuple[float, ...], mass: float,
             values: dict[str, Any]) -> tuple[float, float, dict[str, Any]]:
    """A group's friction, restitution, and the changeDynamics arguments of its bodies."""
    friction_key, restitution_key = default_keys(group.static)
    friction = group.friction if group.friction is not None else values[friction_key]
    restitution = group.restitution if group.restitution is not None else (
        values[restitution_key])
    changes: dict[str, Any] = {"lateralFriction": friction, "restitution": restitution}
    inertia = group_unit_inertia(group, size, mass)
    if inertia is not None:
        # Mass and inertia together: an inertia alone sets a rigid body's mass to 0.
        changes.update(mass=mass, localInertiaDiagonal=[mass * i for i in inertia],
                       ccdSweptSphereRadius=values["pybullet.ccd_swept_sphere_radius"])
    return friction, restitution, changes


def records(group: BodyGroup, ids: list[int], size: tuple[float, ...], mass: float,
          surface: tuple[float, float], batch: int, redo: rebuild.Redo) -> dict[str, Body]:
    """The engine's records of a group's new bodies: everything needed to make them again."""
    friction, restitution = surface
    rgba = None if group.rgba is None else as_rgba(group.rgba)
    inertia = group_unit_inertia(group, size, mass)
    mesh = None if group.vertices is None or group.faces is None else (
        np.asarray(group.vertices, dtype=float), np.asarray(group.faces, dtype=np.int64))
    return {name: Body(uid, group.static, group.shape, size, inertia, batch, mesh=mesh,
                       own_inertia=group.inertia is not None,
                       follows_friction=group.friction is None,
                       follows_restitution=group.restitution is None, mass=mass,
                       friction=friction, restitution=restitution, rgba=rgba,
                       made_mass=mass, turn=redo.turn, turned=turned)
            for name, uid, turned in zip(group.names, ids, redo.turned, strict=True)}
