"""A PyBullet body's physical properties: what ``update`` changes and ``properties`` reads.

Plain functions of the client, its bound ``changeDynamics`` (bound once by the engine:
BulletClient builds a new partial on every attribute access) and the body's records.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.bodies import as_rgba, scale_masses
from galton.daemon.engines.pybullet.rebuild import Body
from galton.protocol import BodyProperties


def edit_spawned(bc: BulletClient, change: Callable[..., Any], body: Body,
                 props: BodyProperties) -> None:
    """A spawned body's new values, remembered in its records (a rebuild gives them again)."""
    dynamics: dict[str, Any] = {}
    if props.mass is not None and body.unit_inertia is not None:
        body.mass = props.mass
        dynamics.update(mass=props.mass,
                        localInertiaDiagonal=[props.mass * i for i in body.unit_inertia])
    if props.friction is not None:
        dynamics["lateralFriction"] = body.friction = props.friction
        body.follows_friction = False
    if props.restitution is not None:
        dynamics["restitution"] = body.restitution = props.restitution
        body.follows_restitution = False
    if dynamics:
        change(body.uid, -1, **dynamics)
    if props.rgba is not None:
        body.rgba = as_rgba(props.rgba)
        bc.changeVisualShape(body.uid, -1, rgbaColor=list(props.rgba))


def edit_model(bc: BulletClient, change: Callable[..., Any], body: Body,
               props: BodyProperties) -> None:
    """A model's mass is its whole body's (every link scaled alike); friction and
    restitution are its base's, the look every link's."""
    if body.model is not None and props.mass is not None and not body.static:
        scale_masses(bc, body.uid, body.model.links, props.mass)
    dynamics = {key: value for key, value in (("lateralFriction", props.friction),
                                              ("restitution", props.restitution))
                if value is not None}
    if dynamics:
        change(body.uid, -1, **dynamics)
    if props.rgba is not None:
        for link in range(-1, body.links):
            bc.changeVisualShape(body.uid, link, rgbaColor=list(props.rgba))


def properties(bc: BulletClient, body: Body) -> tuple[float, float, float]:
    """Mass, friction, restitution: a spawned body's from what the engine last gave PyBullet
    (getDynamicsInfo reports a rigid body's restitution as 0); a model's from PyBullet, the
    mass summed over links. A static body's mass is NaN."""
    if body.shape != "model":
        return (math.nan if body.static else body.mass, body.friction, body.restitution)
    info = bc.getDynamicsInfo(body.uid, -1)
    mass = info[0] + sum(bc.getDynamicsInfo(body.uid, link)[0] for link in range(body.links))
    return (math.nan if body.static else mass, info[1], info[5])
