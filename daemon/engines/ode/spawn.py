"""Making bodies: one ODE geom per entity, on an ODE body unless it is static.

A moving entity is a body whose frame is its centre of mass (every primitive's), with the
mass of its shape at 1000 kg/m³ unless given. A static entity is a geom alone, placed once;
a plane is ODE's infinite plane through the pose, its normal the pose's z axis. A mesh is
an ODE trimesh (trimesh.py); a moving one whose centre of mass is off its origin sits, as a
model's link does, at that centre (``frame``) with its geom offset back.

Collision bits keep pairs that cannot make a contact out of the near-callback (ODE tests
them in C): static geoms collide only with moving ones, and sleeping bodies only with awake
ones (``contacts.Collider`` moves a body between the two as it sleeps and wakes).
"""

from __future__ import annotations

import ctypes
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from galton.daemon.engines.geometry import DENSITY, volume
from galton.daemon.engines.ode import frames
from galton.daemon.engines.ode.frames import Frame
from galton.daemon.engines.ode.native import LIB, Mass, body_state, quaternion
from galton.daemon.engines.ode.trimesh import TriMesh, centred_mass
from galton.protocol import BodyGroup, InvalidArgumentError
from galton.protocol import mesh as mesh_wire
from galton.protocol.vocabulary import POSE_WIDTH, TWIST_WIDTH

AWAKE, STATIC, ASLEEP, RAY = 1, 2, 4, 8
COLLIDES = {AWAKE: AWAKE | STATIC | ASLEEP | RAY, STATIC: AWAKE | RAY, ASLEEP: AWAKE | RAY}


@dataclass
class Body:
    """One entity: its ODE handles and what the engine keeps beside them."""

    name: str
    shape: str
    size: tuple[float, ...]
    static: bool
    geom: int
    body: int  # 0 for a static entity
    mass: float  # NaN for a static entity
    friction: float
    restitution: float
    follows_friction: bool
    follows_restitution: bool
    rgba: tuple[float, float, float, float] | None
    pose: list[float]  # a static entity's pose as given (a moving one reads ODE's)
    state: np.ndarray = field(default_factory=lambda: np.zeros(0))  # ODE's 28 doubles
    awake: bool = True
    model: str | None = None  # the root of the loaded model it belongs to
    serial: int = 0  # its place in the order bodies were made (contacts.Collider)
    extra: list[int] = field(default_factory=list)  # a link's further collision geoms
    frame: Frame | None = None  # a link's centre of mass in its frame (None: at its origin)
    welded: bool = False  # a fixed-base model's root: kinematic, no force moves it
    # Principal moments per kg of a body spawned with its own ``inertia``; None: its shape's.
    unit_inertia: tuple[float, ...] | None = None
    # A link's collision shapes in its frame, as get_shapes tells them (kind, half sizes,
    # pose x y z qx qy qz qw); a spawned body's are its shape and size.
    link_shapes: list[tuple[str, tuple[float, ...], tuple[float, ...]]] = \
        field(default_factory=list)
    mesh: TriMesh | None = None  # a mesh's arrays and ODE data, alive as long as its geom
    unit_mass: Mass | None = None  # a moving mesh's mass per kg about its centre

    def geoms(self) -> list[int]:
        return ([self.geom] if self.geom else []) + self.extra

    def set_bits(self, kind: int) -> None:
        for geom in self.geoms():
            LIB.dGeomSetCategoryBits(geom, kind)
            LIB.dGeomSetCollideBits(geom, COLLIDES[kind])




def mass_of(shape: str, size: tuple[float, ...], total: float) -> Mass:
    """ODE's mass of a solid primitive of that total, about its centre, axis along z."""
    mass = Mass()
    address = ctypes.addressof(mass)
    if shape == "sphere":
        LIB.dMassSetSphereTotal(address, total, size[0])
    elif shape in ("box", "mesh"):  # a mesh enclosing no volume: its bounding box's
        LIB.dMassSetBoxTotal(address, total, 2 * size[0], 2 * size[1], 2 * size[2])
    elif shape == "cylinder":
        LIB.dMassSetCylinderTotal(address, total, 3, size[0], 2 * size[1])
    else:
        LIB.dMassSetCapsuleTotal(address, total, 3, size[0], 2 * size[1])
    return mass


def make_geom(space: int, shape: str, size: tuple[float, ...],
              mesh: TriMesh | None = None) -> int:
    if mesh is not None:
        return mesh.geom(space)
    if shape == "sphere":
        return int(LIB.dCreateSphere(space, size[0]))
    if shape == "box":
        return int(LIB.dCreateBox(space, 2 * size[0], 2 * size[1], 2 * size[2]))
    if shape == "cylinder":
        return int(LIB.dCreateCylinder(space, size[0], 2 * size[1]))
    if shape == "capsule":
        return int(LIB.dCreateCapsule(space, size[0], 2 * size[1]))
    raise InvalidArgumentError(f"the ode engine cannot make a {shape!r}")


def place_static(body: Body, pose: list[float]) -> None:
    """Put a static geom at ``pose`` (a plane: through it, normal along its z axis)."""
    body.pose = [float(v) for v in pose]
    if body.shape == "plane":
        normal = _z_axis(pose[3:])
        LIB.dGeomPlaneSetParams(body.geom, *normal, float(np.dot(normal, pose[:3])))
        return
    LIB.dGeomSetPosition(body.geom, *pose[:3])
    LIB.dGeomSetQuaternion(body.geom, quaternion(pose[3:]))


def _z_axis(xyzw: list[float]) -> np.ndarray:
    x, y, z, w = xyzw
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])


def spawn_group(world: int, space: int, group: BodyGroup, values: dict[str, Any]
                ) -> list[Body]:
    """Every body of the group, in order; on failure, none (what was made is destroyed)."""
    if group.shape == "plane" and not group.static:
        raise InvalidArgumentError("a plane must be static")
    size = tuple(float(s) for s in group.size)
    poses = np.asarray(group.poses, dtype=float).reshape(-1, POSE_WIDTH).tolist()
    twists = None if group.twists is None else np.asarray(
        group.twists, dtype=float).reshape(-1, TWIST_WIDTH).tolist()
    friction_key, restitution_key = default_key_pair(group.static)
    made: list[Body] = []
    try:
        for k, name in enumerate(group.names):
            mesh = None if group.vertices is None or group.faces is None else \
                TriMesh.build(group.vertices, group.faces)
            body = Body(name, group.shape, size, group.static, 0, 0, math.nan,
                        values[friction_key] if group.friction is None else group.friction,
                        values[restitution_key] if group.restitution is None
                        else group.restitution,
                        group.friction is None, group.restitution is None, group.rgba,
                        poses[k], mesh=mesh)
            made.append(body)
            if group.static:
                make_static(space, body)
            else:
                total = group.mass if group.mass is not None else DENSITY * (
                    volume(group.shape, size) if mesh is None
                    else mesh_wire.volume(mesh.vertices, mesh.indices))
                if group.inertia is not None:
                    body.unit_inertia = tuple(i / total for i in group.inertia)
                make_moving(world, space, body, float(total), poses[k],
                            None if twists is None else twists[k])
    except BaseException:
        destroy(made)
        raise
    return made


def default_key_pair(static: bool) -> tuple[str, str]:
    if static:
        return "default_static_friction", "default_static_restitution"
    return "default_friction", "default_restitution"


def make_static(space: int, body: Body) -> None:
    body.geom = (int(LIB.dCreatePlane(space, 0.0, 0.0, 1.0, 0.0)) if body.shape == "plane"
                 else make_geom(space, body.shape, body.size, body.mesh))
    body.set_bits(STATIC)
    place_static(body, body.pose)


def make_moving(world: int, space: int, body: Body, total: float, pose: list[float],
                twist: list[float] | None) -> None:
    body.body = int(LIB.dBodyCreate(world))
    body.geom = make_geom(space, body.shape, body.size, body.mesh)
    if body.mesh is not None:
        _centre_mesh(body)
    LIB.dGeomSetBody(body.geom, body.body)
    if body.frame is not None:
        LIB.dGeomSetOffsetPosition(body.geom, *(-body.frame[0]))
        at, turn = frames.compose((np.asarray(pose[:3]), np.asarray(pose[3:])), body.frame)
        pose = [*at.tolist(), *turn.tolist()]
    set_mass(body, total)
    body.set_bits(AWAKE)
    body.state = np.ctypeslib.as_array(body_state(body.body))
    LIB.dBodySetPosition(body.body, *pose[:3])
    LIB.dBodySetQuaternion(body.body, quaternion(pose[3:]))
    if twist is not None:
        LIB.dBodySetLinearVel(body.body, *twist[:3])
        LIB.dBodySetAngularVel(body.body, *twist[3:])
    body.pose = []


def _centre_mesh(body: Body) -> None:
    """A moving mesh's mass per kg about its centre of mass (ODE's integral over its
    triangles; its bounding box's where it encloses no volume), and that centre's frame."""
    assert body.mesh is not None
    found = centred_mass(body.geom, body.mesh.vertices, body.mesh.indices, 1.0)
    if found is None:
        return  # the shape's mass: a box of the mesh's half extents (mass_of)
    body.unit_mass, centre = found
    if np.any(centre != 0.0):
        body.frame = (centre, frames.IDENTITY[1].copy())


def set_mass(body: Body, total: float) -> None:
    """The body's mass, and its inertia at that mass: its own (scaled) or its shape's."""
    if body.unit_inertia is not None:
        mass = Mass()
        ixx, iyy, izz = (total * i for i in body.unit_inertia)
        LIB.dMassSetParameters(ctypes.addressof(mass), total, 0.0, 0.0, 0.0, ixx, iyy, izz,
                               0.0, 0.0, 0.0)
    elif body.unit_mass is not None:
        mass = Mass()
        ctypes.memmove(ctypes.addressof(mass), ctypes.addressof(body.unit_mass),
                       ctypes.sizeof(Mass))
        LIB.dMassAdjust(ctypes.addressof(mass), total)
    else:
        mass = mass_of(body.shape, body.size, total)
    LIB.dBodySetMass(body.body, ctypes.addressof(mass))
    body.mass = total


def destroy(bodies: list[Body]) -> None:
    """Free the geoms and bodies (a body's contact joints go with the next step's empty)."""
    for body in bodies:
        for geom in body.geoms():
            LIB.dGeomDestroy(geom)
        body.geom, body.extra = 0, []
        if body.mesh is not None:
            body.mesh.release()
        if body.body:
            LIB.dBodyDestroy(body.body)
            body.body = 0
        body.state = np.zeros(0)
