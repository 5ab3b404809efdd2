"""Rebuilding a PyBullet world to free what removeBody keeps.

removeBody leaves about 0.85 kB per removed body inside Bullet until resetSimulation, so a
world that keeps some bodies while others come and go grows without end. The engine counts
the bodies removed since the last rebuild; once they pass ``REBUILD_AFTER`` (or twice the
bodies left, so that a rebuild's cost stays small beside the deletes that led to it) it
reads every remaining body, calls resetSimulation, re-applies the world settings and makes
each body again: shape, size, look, mass and inertia, friction, restitution, collision
margin, CCD, pose and twist, under the same entity name (with a new PyBullet id).

A pose read back from Bullet is a rotation matrix turned into a quaternion, and setting that
quaternion does not always give the same matrix back: about a third of the turned bodies
read back a quaternion one or two units in the last place off. ``place`` corrects the
quaternion a few times; a body still off after that keeps its exact old state as what
``get_states`` reports until its state is next set or the world steps (the simulation goes
on from a pose that differs by rounding only).

Worlds that hold bodies of a loaded model are not rebuilt (a model's joints, link states
and file would all have to be restored): there removeBody's leak stays.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet_shapes import BodyMaker, ShapeCache, margin_for

REBUILD_AFTER = 5_000  # bodies removed since the last rebuild, at the least
PLACE_TRIES = 4  # quaternion corrections before a pose is held instead

State = tuple[list[float], list[float]]  # pose (7), twist (6)
Held = tuple[list[float] | None, list[float] | None]  # the pose, twist or both to report


@dataclass(slots=True)
class Body:
    """What the engine keeps per entity beyond PyBullet's body id: for spawned bodies,
    everything needed to make the body again."""

    uid: int
    static: bool
    shape: str  # a protocol shape, or "model"
    size: tuple[float, ...]
    unit_inertia: tuple[float, float, float] | None  # None for static bodies
    links: int = 0  # a model's links beside the base
    follows_friction: bool = False  # set by default_(static_)friction, now and after a change
    follows_restitution: bool = False
    mass: float = 0.0  # spawned bodies: what PyBullet was last given (0 when static)
    friction: float = 0.0
    restitution: float = 0.0
    rgba: tuple[float, ...] | None = None  # None: the default look


def due(removed: int, live: dict[str, Body]) -> bool:
    """Whether enough bodies went to make a rebuild worth it, and it can be done."""
    if removed < max(REBUILD_AFTER, 2 * len(live)):
        return False
    return not any(body.shape == "model" for body in live.values())


def read_states(bc: BulletClient, bodies: dict[str, Body]) -> dict[str, State]:
    """Each body's pose and twist, as PyBullet reports them."""
    states = {}
    for name, body in bodies.items():
        position, orientation = bc.getBasePositionAndOrientation(body.uid)
        linear, angular = bc.getBaseVelocity(body.uid)
        states[name] = ([*position, *orientation], [*linear, *angular])
    return states


def place(bc: BulletClient, uid: int, pose: list[float]) -> bool:
    """Set a body's pose so that it reads back as ``pose``; False where rounding defeats it."""
    want = (tuple(pose[:3]), tuple(pose[3:]))
    quaternion = list(pose[3:])
    for _ in range(PLACE_TRIES):
        bc.resetBasePositionAndOrientation(uid, pose[:3], quaternion)
        got = bc.getBasePositionAndOrientation(uid)
        if got == want:
            return True
        quaternion = [q + (w - g) for q, w, g in zip(quaternion, want[1], got[1], strict=True)]
    bc.resetBasePositionAndOrientation(uid, pose[:3], pose[3:])
    return False


def recreate(bc: BulletClient, maker: BodyMaker, shapes: ShapeCache, bodies: dict[str, Body],
             states: dict[str, State], values: dict[str, Any]) -> dict[str, Held]:
    """Make the spawned ``bodies`` again in a freshly reset world, giving each its new id.
    Returns the states of those that do not read back bit for bit (see the module doc)."""
    groups: dict[tuple[Any, ...], list[str]] = {}
    for name, body in bodies.items():
        groups.setdefault((body.shape, body.size, body.rgba, body.mass), []).append(name)
    made: list[int] = []
    for (shape, size, rgba, mass), names in groups.items():
        ids = maker.create(mass, shapes.get(shape, size), shapes.visual(shape, size, rgba),
                           [states[n][0][:3] for n in names], states[names[0]][0][3:],
                           set(), made)
        for name, uid in zip(names, ids, strict=True):
            bodies[name].uid = uid
    held: dict[str, Held] = {}
    margins: set[tuple[str, tuple[float, ...]]] = set()
    for name, body in bodies.items():
        dynamics: dict[str, Any] = {"lateralFriction": body.friction,
                                    "restitution": body.restitution}
        if not body.static and body.unit_inertia is not None:
            dynamics.update(mass=body.mass,
                            localInertiaDiagonal=[body.mass * i for i in body.unit_inertia],
                            ccdSweptSphereRadius=values["pybullet.ccd_swept_sphere_radius"])
        bc.changeDynamics(body.uid, -1, **dynamics)
        pose, twist = states[name]
        exact = place(bc, body.uid, pose)
        bc.resetBaseVelocity(body.uid, twist[:3], twist[3:])
        linear, angular = bc.getBaseVelocity(body.uid)
        twist_exact = [*linear, *angular] == twist
        if not (exact and twist_exact):
            held[name] = (None if exact else pose, None if twist_exact else twist)
        if (body.shape, body.size) not in margins:
            margins.add((body.shape, body.size))
            margin = margin_for(body.shape, body.size, values["pybullet.collision_margin"])
            if margin is not None:
                bc.changeDynamics(body.uid, -1, collisionMargin=margin)
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
