"""Rebuilding a PyBullet world: resetSimulation, then every body made again as it was.

Two things need it. removeBody leaves about 0.9 kB per removed body inside Bullet until
resetSimulation, so a world that keeps some bodies while others come and go grows without
end: once the bodies removed since the last rebuild pass ``REBUILD_AFTER`` (or twice the
bodies left, so that a rebuild's cost stays small beside the deletes that led to it) the
engine rebuilds. And a rewound world (``reset_dynamics``, after ``stop`` set every body
back to its created state) must replay its first run bit for bit: Bullet keeps contact
points with their warm-start impulses across a teleport, so only a new world forgets the
run before.

A rebuild makes the bodies again in the order they were first made, batch by batch (a
spawn group, a model load), through the same calls as the first time: shape, size, look,
mass and inertia, friction, restitution, collision margin, CCD, pose and twist, under the
same entity name (with a new PyBullet id); each body with the mass and orientation it was
first made with, since Bullet's first step still uses the inertia (in world axes) of the
body as made, and then given what has changed since. So a rewound world is the same world,
bit for bit, however long it ran before: replays after a stop agree with each other always,
and with the first run whenever that started from the created states (the World's stop
sets them), with spawns, updates, parameters, deletes and model loads before it. One
exception is known: a change of ``pybullet.collision_margin`` between making boxes or
cylinders and the first run (Bullet keeps a box's extents less its margin, rounded anew at
each change: 2e-4 m apart after 600 steps of a tumbling scene).

A pose is set again from the value last given to PyBullet (spawn, ``set_states``) when the
world has not stepped since; otherwise it is read back, a rotation matrix turned into a
quaternion, and setting that quaternion does not always give the same matrix back: about a
third of the turned bodies read back a quaternion one or two units in the last place off.
``place`` corrects the quaternion a few times; a body still off after that keeps its exact
old state as what ``get_states`` reports until its state is next set or the world steps
(the simulation goes on from a pose that differs by rounding only).

Loaded models are loaded again from their text, with the changes ``update`` made since,
their joints set again to the states they had (left as loaded where they are as loaded, so
that a rewound model replays its first run bit for bit), their targets and held wrenches
kept (the records are by name). A world holding a model is still not rebuilt to free
deleted bodies: the contact caches its joints rely on would go; removeBody's leak stays.
"""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.bodies import WHITE, Link, load_bodies
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    InvalidArgumentError,
    OperationFailedError,
)

if TYPE_CHECKING:
    from collections.abc import Callable

    from galton.daemon.engines.pybullet.engine import PybulletEngine
    from galton.daemon.engines.pybullet.frames import Offset
    from galton.daemon.engines.pybullet.robots import JointStates, Robots

REBUILD_AFTER = 5_000  # bodies removed since the last rebuild, at the least
PLACE_TRIES = 4  # quaternion corrections before a pose is held instead

State = tuple[list[float], list[float]]  # pose (7), twist (6)
Held = tuple[list[float] | None, list[float] | None]  # the pose, twist or both to report


@dataclass(slots=True)
class Model:
    """Where a loaded body came from, to load it again."""

    fmt: str
    text: str
    path: str | None  # loaded from this file (its relative mesh paths need it)
    index: int  # the body's place among those the load made
    links: tuple[Link, ...]  # base first, as loaded: ``update(mass=...)`` scales these
    loaded: State  # the state it was loaded in, as read back
    edits: BodyProperties = field(default_factory=BodyProperties)  # the latest of each
    fixed_base: bool = False  # a URDF's root welded to the world


@dataclass(frozen=True, slots=True)
class Redo:
    """How a rebuild makes a spawn group again: the orientation its bodies were made with,
    and which of them then take their own."""

    turn: tuple[float, ...]
    turned: list[bool]


@dataclass(slots=True)
class Body:
    """What the engine keeps per entity beyond PyBullet's body id: everything needed to make
    the body again."""

    uid: int
    static: bool
    shape: str  # a protocol shape, or "model"
    size: tuple[float, ...]
    unit_inertia: tuple[float, float, float] | None  # None for static bodies and models
    batch: int = 0  # the spawn group or model load that made it
    links: int = 0  # a model's links beside the base
    follows_friction: bool = False  # set by default_(static_)friction, now and after a change
    follows_restitution: bool = False
    mass: float = 0.0  # spawned bodies: what PyBullet was last given (0 when static)
    # The mass it was made with. Bullet computes a body's inertia in world axes when it
    # makes it and again only at the end of a step, so the first step after a mass change
    # still uses the old one: a rebuild makes the body with this mass, then sets ``mass``.
    made_mass: float = 0.0
    # The orientation it was made with, and whether spawn then turned it to its own (a
    # group of several orientations): Bullet's first step uses the inertia of the body as
    # made, in world axes, and a quaternion given to createMultiBody makes a matrix a few
    # units in the last place off the one resetBasePositionAndOrientation makes.
    turn: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)
    turned: bool = False
    friction: float = 0.0
    restitution: float = 0.0
    rgba: tuple[float, float, float, float] | None = None  # None: the default look
    model: Model | None = None
    mesh: tuple[np.ndarray, np.ndarray] | None = None  # a mesh's vertices and faces
    own_inertia: bool = False  # unit_inertia came with the spawn (its ``inertia``)


@dataclass(slots=True)
class Plan:
    """Everything a rebuild makes a world again from: the bodies' records in the order they
    were made, their states (``exact``: poses given since the last step, set as given),
    the models' articulations, inertial offsets and 1-DOF joint states."""

    bodies: dict[str, Body]
    states: dict[str, State]
    exact: set[str]
    robots: Robots
    frames: dict[str, Offset]
    joints: JointStates


def due(removed: int, live: dict[str, Body]) -> bool:
    """Whether enough bodies went to make a rebuild worth it, and it can be done."""
    if removed < max(REBUILD_AFTER, 2 * len(live)):
        return False
    return not any(body.model is not None for body in live.values())


def read_states(bc: BulletClient, bodies: dict[str, Body], given: dict[str, list[float]],
                held: dict[str, Held]) -> dict[str, State]:
    """Each body's pose and twist to make it with: a pose given since the last step as it
    was given, a held state as held, the rest as PyBullet reports it."""
    states = {}
    # Bound once: BulletClient builds a new functools.partial on every attribute access.
    get_pose, get_velocity = bc.getBasePositionAndOrientation, bc.getBaseVelocity
    for name, body in bodies.items():
        position, orientation = get_pose(body.uid)
        linear, angular = get_velocity(body.uid)
        pose, twist = held.get(name, (None, None))
        states[name] = (given.get(name) or pose or [*position, *orientation],
                        twist or [*linear, *angular])
    return states


def batches(bodies: dict[str, Body]) -> Iterator[list[str]]:
    """The bodies in the order they were made, in runs that one call makes again: what is
    left of one spawn group or of one model load."""
    for _, run in itertools.groupby(bodies, key=lambda name: bodies[name].batch):
        yield list(run)


def as_group(names: list[str], bodies: dict[str, Body],
             states: dict[str, State]) -> tuple[BodyGroup, Redo]:
    """What is left of a spawn group, as the group that makes it again (with the first
    body's values) and how: a body is turned when it was or when its turn has changed."""
    body = bodies[names[0]]
    group = BodyGroup(body.shape, body.size, names,
                      np.array([states[n][0] for n in names], dtype=float),
                      twists=np.array([states[n][1] for n in names], dtype=float),
                      static=body.static, mass=None if body.static else body.made_mass,
                      friction=body.friction, restitution=body.restitution, rgba=body.rgba,
                      vertices=None if body.mesh is None else body.mesh[0],
                      faces=None if body.mesh is None else body.mesh[1],
                      inertia=own_inertia(body))
    turned = [bodies[n].turned or tuple(states[n][0][3:]) != body.turn for n in names]
    return group, Redo(body.turn, turned)


def own_inertia(body: Body) -> tuple[float, float, float] | None:
    """The inertia a body was spawned with (kg m²), None where it is its shape's."""
    if not body.own_inertia or body.unit_inertia is None:
        return None
    ixx, iyy, izz = (body.made_mass * i for i in body.unit_inertia)
    return (ixx, iyy, izz)


def changes(old: Body, new: Body) -> BodyProperties | None:
    """What sets a body made again to the values it had, or None when it has them."""
    props = BodyProperties(
        mass=old.mass if old.mass != new.mass else None,
        friction=old.friction if old.friction != new.friction else None,
        restitution=old.restitution if old.restitution != new.restitution else None,
        rgba=(old.rgba or WHITE) if old.rgba != new.rgba else None)
    return None if props == BodyProperties() else props


def place(bc: BulletClient, uid: int, pose: list[float]) -> bool:
    """Set a body's pose so that it reads back as ``pose``; False where rounding defeats it.
    Either way the body's twist is zero after it (resetBasePositionAndOrientation's doing)."""
    want = (tuple(pose[:3]), tuple(pose[3:]))
    quaternion = list(pose[3:])
    reset, get = bc.resetBasePositionAndOrientation, bc.getBasePositionAndOrientation
    for _ in range(PLACE_TRIES):
        reset(uid, pose[:3], quaternion)
        got = get(uid)
        if got == want:
            return True
        quaternion = [q + (w - g) for q, w, g in zip(quaternion, want[1], got[1], strict=True)]
    reset(uid, pose[:3], pose[3:])
    return False


def settle(bc: BulletClient, bodies: dict[str, Body], states: dict[str, State],
           exact: set[str]) -> dict[str, Held]:
    """Correct the poses of bodies made again from read-back states (those not in
    ``exact``); return the states of those that still do not read back bit for bit."""
    held: dict[str, Held] = {}
    get_pose, reset_velocity = bc.getBasePositionAndOrientation, bc.resetBaseVelocity
    for name, body in bodies.items():
        pose, twist = states[name]
        if name in exact or get_pose(body.uid) == (tuple(pose[:3]), tuple(pose[3:])):
            continue
        if not place(bc, body.uid, pose):
            held[name] = (pose, None)
        reset_velocity(body.uid, twist[:3], twist[3:])
    return held


def report_held(held: dict[str, Held], names: Sequence[str], poses: np.ndarray,
                twists: np.ndarray) -> None:
    """Put the held states of these bodies in the arrays ``get_states`` returns."""
    for k, name in enumerate(names):
        pose, twist = held.get(name, (None, None))
        if pose is not None:
            poses[k] = pose
        if twist is not None:
            twists[k] = twist


def release_held(held: dict[str, Held], names: Sequence[str], poses: bool,
                 twists: bool) -> None:
    """Forget what ``set_states`` sets now (it reads back as it is from then on)."""
    for name in names:
        if name in held:
            pose, twist = held.pop(name)
            pose, twist = (None if poses else pose), (None if twists else twist)
            if pose is not None or twist is not None:
                held[name] = (pose, twist)


def merged(edits: BodyProperties, props: BodyProperties) -> BodyProperties:
    """The latest value of each property ``update`` has set on a model body."""
    return dataclasses.replace(edits, **{
        key: value for key in ("mass", "friction", "restitution", "rgba")
        if (value := getattr(props, key)) is not None})


def rebuild(engine: PybulletEngine) -> None:
    """resetSimulation, then every body made again, in the order it was first made, as
    the protocol sees it (see the module's docstring)."""
    make_again(engine, read_plan(engine))


def read_plan(engine: PybulletEngine) -> Plan:
    """What a rebuild makes the world again from, read from the world as it is."""
    kept = dict(engine.bodies)
    return Plan(kept, read_states(engine._bc, kept, engine.given, engine.held),
                set(engine.given), engine.robots, engine.frames,
                engine.robots.snapshot(engine._bc, engine._uid_of))


def make_again(engine: PybulletEngine, plan: Plan, check: Callable[[], None] | None = None) -> None:
    """A new world holding what ``plan`` describes: the same calls, in the same order,
    whether the plan was read from this world or from a snapshot of another (whose
    ``check`` then looks at the bodies made before joints are set)."""
    kept, states = plan.bodies, plan.states
    engine.clear()
    for names in batches(kept):
        if kept[names[0]].model is not None:
            reload(engine, names, kept, states)
        else:
            remake(engine, names, kept, states)
    if check is not None:
        check()
    engine.robots, engine.frames = plan.robots, plan.frames
    plan.robots.put_back(engine._bc, engine._uid_of, plan.joints)
    engine.held = settle(engine._bc, engine.bodies, states, plan.exact)
    engine.given = {name: states[name][0] for name in plan.exact}
    engine.rebuilds += 1


def remake(engine: PybulletEngine, names: list[str], kept: dict[str, Body],
           states: dict[str, State]) -> None:
    """A spawn group's remaining bodies made again as spawn first made them, then given
    what update or a default has changed since."""
    group, redo = as_group(names, kept, states)
    bodies = engine._spawn_group(group, [], kept[names[0]].batch, redo)
    for name, body in bodies.items():
        old = kept[name]
        fixes = changes(old, body)
        if fixes is not None:
            engine._edit_spawned(body, fixes)
        body.follows_friction = old.follows_friction
        body.follows_restitution = old.follows_restitution
        body.turned, body.rgba = old.turned, old.rgba
    engine.bodies.update(bodies)


def reload(engine: PybulletEngine, names: list[str], kept: dict[str, Body],
           states: dict[str, State]) -> None:
    """A model loaded again from its text, the bodies
    deleted since its load removed again, the others restored."""
    models = {name: model for name in names if (model := kept[name].model) is not None}
    first = models[names[0]]
    try:
        ids = load_bodies(engine._bc, engine._maker, first.fmt, first.text, None,
                          first.fixed_base)
    except InvalidArgumentError as exc:  # its meshes gone?
        raise OperationFailedError(f"a model could not be loaded again: {exc}") from exc
    wanted = {model.index: name for name, model in models.items()}
    for index, uid in enumerate(ids):
        name = wanted.get(index)
        if name is None:
            engine._maker.remove([uid])
        else:
            restore_model_body(engine, uid, name, kept[name].batch, models[name],
                                     states[name])


def restore_model_body(engine: PybulletEngine, uid: int, name: str, batch: int, model: Model,
                       state: State) -> None:
    """A body loaded again, given what update changed and its state; its joints are
    back as loaded, at rest. A state as loaded is not set again: a pose read back and
    set makes a matrix a unit in the last place off the loaded one."""
    body = engine._adopt_model_body(uid, name, batch)
    if len(model.links) != body.links + 1:  # only a snapshot from elsewhere can differ
        raise InvalidArgumentError(f"the records of model body {name!r} list "
                                   f"{len(model.links)} links; its text makes "
                                   f"{body.links + 1}")
    body.model = model
    engine._edit_model(body, model.edits)
    if state != model.loaded:
        pose, twist = state
        engine.reset_pose(uid, pose[:3], pose[3:])
        engine.reset_velocity(uid, twist[:3], twist[3:])
