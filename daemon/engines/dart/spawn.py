"""A DART world's bodies: what the engine keeps of each (its records), how a spawned body
becomes a one-link skeleton, and how a world is set up as gz-physics sets one up.

Every spawned body is its own skeleton: a free joint holding one body node with one shape
node (collision, visual and dynamics aspects), made immobile when static. A loaded model is
one skeleton whose root and links are entities too (models.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import dartpy as dart
import numpy as np

from galton.daemon.engines.dart.params import PARAMS
from galton.daemon.engines.geometry import default_mass
from galton.protocol import BodyGroup

SPAWNED, MODEL = "b:", "m:"  # skeleton name prefixes: unique, whatever entities are named


@dataclass
class Body:
    """One entity: a spawned body (its own skeleton) or a model's root or link."""

    name: str
    shape: str
    size: tuple[float, ...]
    static: bool
    mass: float
    friction: float
    restitution: float
    follows_friction: bool  # set none: follows the default parameter
    follows_restitution: bool
    skeleton: Any  # dart.dynamics.Skeleton
    node: Any  # dart.dynamics.BodyNode
    rgba: tuple[float, ...] | None = None
    model: str | None = None  # the root's name, for a model's root and links
    links: list[str] = field(default_factory=list)  # a root's other links
    # Principal moments per kg of a body spawned with its own ``inertia``; None: its shape's.
    unit_inertia: tuple[float, ...] | None = None
    # A mesh's vertices and faces (for snapshots) and its DART MeshShape (meshes.py), which
    # the bodies of one spawn group share.
    mesh: tuple[np.ndarray, np.ndarray] | None = None
    mesh_shape: Any = None


def make_shape(shape: str, size: tuple[float, ...]) -> Any:
    """The DART shape of a protocol shape (half sizes; cylinders and capsules along z)."""
    if shape == "sphere":
        return dart.dynamics.SphereShape(size[0])
    if shape == "box":
        return dart.dynamics.BoxShape([2.0 * s for s in size])
    if shape == "cylinder":
        return dart.dynamics.CylinderShape(size[0], 2.0 * size[1])
    if shape == "capsule":
        return dart.dynamics.CapsuleShape(size[0], 2.0 * size[1])
    return dart.dynamics.PlaneShape(np.array([0.0, 0.0, 1.0]), 0.0)


def group_values(group: BodyGroup, values: dict[str, Any]) -> tuple[float, float, float]:
    """Each body's mass (NaN when static), friction and restitution."""
    mass = math.nan if group.static else default_mass(group)
    kind = "default_static_" if group.static else "default_"
    friction = group.friction if group.friction is not None else values[kind + "friction"]
    restitution = group.restitution if group.restitution is not None else (
        values[kind + "restitution"])
    return mass, float(friction), float(restitution)


def build(body: Body, positions: np.ndarray, velocities: np.ndarray) -> None:
    """Make a spawned body's skeleton (its records already filled) at this free-joint state."""
    skeleton = dart.dynamics.Skeleton(SPAWNED + body.name)
    _, node = skeleton.createFreeJointAndBodyNodePair()
    node.setName(body.name)
    shape = body.mesh_shape if body.mesh_shape is not None else make_shape(body.shape,
                                                                             body.size)
    shape_node = node.createShapeNode(shape)
    shape_node.createCollisionAspect()
    shape_node.createDynamicsAspect()
    body.skeleton, body.node = skeleton, node
    set_surface(body)
    if not body.static:
        set_mass(body, body.mass)
    skeleton.setPositions(positions)
    skeleton.setVelocities(velocities)
    if body.static:
        skeleton.setMobile(False)


def set_surface(body: Body) -> None:
    """Friction and restitution on every shape of the body's node."""
    for k in range(body.node.getNumShapeNodes()):
        aspect = body.node.getShapeNode(k).getDynamicsAspect()
        if aspect is not None:
            aspect.setFrictionCoeff(body.friction)
            aspect.setRestitutionCoeff(body.restitution)


def set_mass(body: Body, mass: float) -> None:
    """A spawned body's mass and the inertia at that mass: its own (spawn's ``inertia``,
    scaled with the mass) or its solid shape's (a mesh: its bounding box's, DART's
    ``MeshShape::computeInertia``)."""
    if body.unit_inertia is not None:
        moment = np.diag(np.asarray(body.unit_inertia, dtype=float) * mass)
    else:
        moment = body.node.getShapeNode(0).getShape().computeInertia(mass)
    inertia = dart.dynamics.Inertia(mass, np.zeros(3), moment)
    body.node.setInertia(inertia)
    body.mass = mass


def new_world(values: dict[str, Any]) -> Any:
    """An empty DART world set up as gz-physics' ConstructEmptyWorld sets one up: the ODE
    collision detector (dartsim/src/EntityManagementFeatures.cc), then these values."""
    world = dart.simulation.World()
    configure(world, values)
    return world


DETECTOR_CLASSES = {"ode": "OdeCollisionDetector", "fcl": "FCLCollisionDetector",
                    "bullet": "BulletCollisionDetector", "dart": "DARTCollisionDetector"}


def configure(world: Any, values: dict[str, Any]) -> None:
    """Hand the world-level values to DART (the others reach bodies)."""
    world.setTimeStep(float(values["timestep"]))
    world.setGravity(np.asarray(values["gravity"], dtype=float))
    sleep = world.getDeactivationOptions()
    sleep.mEnabled = bool(values["dart.sleep"])
    world.setDeactivationOptions(sleep)
    solver = world.getConstraintSolver()
    detector = getattr(dart.collision, DETECTOR_CLASSES[values["dart.collision_detector"]])
    fallback = dart.constraint.PgsBoxedLcpSolverOption()
    fallback.mMaxIteration = int(values["solver_iterations"])
    solver.getSecondaryBoxedLcpSolver().setOption(fallback)
    if solver.getCollisionDetector().getType() != detector.getStaticType():
        solver.setCollisionDetector(detector())


def defaults() -> dict[str, Any]:
    return {name: spec.default for name, spec in PARAMS.items()}
