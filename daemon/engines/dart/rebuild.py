"""Rebuilding a DART world afresh from the same skeletons, and what a rebuild needs: the
entities' records, the order skeletons were made in, models and their edits.

Functions of the engine (``DartEngine`` calls them; it holds the records: ``_bodies``,
``_owners`` (spawned bodies and model roots, in the order they were made), ``_models``,
``_edits`` (per model root, in order)).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.dart import joints as model_joints
from galton.daemon.engines.dart import models
from galton.daemon.engines.dart import spawn as spawning
from galton.daemon.engines.dart.contacts import node_key
from galton.protocol import (
    BodyProperties,
    EntityInfo,
    NameNotUniqueError,
    NotFoundError,
)

if TYPE_CHECKING:
    from galton.daemon.engines.dart.engine import DartEngine

SURFACE_DEFAULTS = ("default_friction", "default_restitution", "default_static_friction",
                    "default_static_restitution")


def init_records(engine: DartEngine) -> None:
    engine._owners, engine._models, engine._edits = [], {}, {}


def check_new(engine: DartEngine, names: Sequence[str]) -> None:
    seen: set[str] = set()
    for name in names:
        if name in engine._bodies or name in seen:
            raise NameNotUniqueError(f"an entity named {name!r} already exists")
        seen.add(name)


def lookup(engine: DartEngine, names: Sequence[str]) -> list[spawning.Body]:
    try:
        return [engine._bodies[n] for n in names]
    except KeyError as exc:
        raise NotFoundError(f"no entity named {exc.args[0]!r} in the DART world") from None


def add(engine: DartEngine, body: spawning.Body) -> None:
    engine._bodies[body.name] = body
    engine._owners.append(body.name)
    engine._world.addSkeleton(body.skeleton)


def remove(engine: DartEngine, body: spawning.Body) -> None:
    """A spawned body, or a model's root with its links, joints and wrenches."""
    engine._world.removeSkeleton(body.skeleton)
    engine._owners.remove(body.name)
    for name in [body.name, *body.links]:
        del engine._bodies[name]
        engine._robots.wrenches.pop(name, None)
    if body.model is not None:
        engine._robots.forget_model(body.name)
        engine._models.pop(body.name, None)
        engine._edits.pop(body.name, None)


def rebuild(engine: DartEngine) -> None:
    """A new world with the same skeletons, added in the order they were made."""
    world = spawning.new_world(engine._values)
    for owner in engine._owners:
        skeleton = engine._bodies[owner].skeleton
        engine._world.removeSkeleton(skeleton)
        world.addSkeleton(skeleton)
    engine._world = world


def entity_keys(engine: DartEngine) -> dict[tuple[str, str], str]:
    keys = {}
    for body in engine._bodies.values():
        keys[node_key(body.node)] = body.name
    return keys

def body_properties(engine: DartEngine, body: spawning.Body) -> tuple[float, float, float]:
    if body.model is None:
        return (math.nan if body.static else body.mass), body.friction, body.restitution
    mass = math.nan if body.static else (
        float(body.skeleton.getMass()) if body.name == body.model
        else float(body.node.getMass()))
    return mass, body.friction, body.restitution


def edit(engine: DartEngine, body: spawning.Body, props: BodyProperties) -> None:
    if body.model is not None:
        engine._edits.setdefault(body.model, []).append((body.name, props))
        edit_model(engine._bodies, body, props)
        return
    if props.mass is not None:
        spawning.set_mass(body, float(props.mass))
    if props.friction is not None:
        body.friction, body.follows_friction = float(props.friction), False
    if props.restitution is not None:
        body.restitution, body.follows_restitution = float(props.restitution), False
    if props.rgba is not None:
        body.rgba = tuple(props.rgba)
    spawning.set_surface(body)


def follow_defaults(engine: DartEngine, changed: dict[str, Any]) -> None:
    """Spawned bodies that set no friction or restitution take their kind's new one."""
    if not changed.keys() & set(SURFACE_DEFAULTS):
        return
    for body in engine._bodies.values():
        if body.model is not None:
            continue
        kind = "default_static_" if body.static else "default_"
        if body.follows_friction:
            body.friction = float(engine._values[kind + "friction"])
        if body.follows_restitution:
            body.restitution = float(engine._values[kind + "restitution"])
        spawning.set_surface(body)

def load(engine: DartEngine, fmt: str, text: str | None, path: str | None, prefix: str,
         fixed_base: bool) -> list[EntityInfo]:
    models.check_format(fmt)
    source = models.model_text(text, path)
    skeletons = models.parse(fmt, source, fixed_base)
    names = [n for s in skeletons for n in models.link_names(s, prefix)]
    check_new(engine, names)
    infos: list[EntityInfo] = []
    for index, skeleton in enumerate(skeletons):
        infos.extend(add_model(engine, models.Model(
            models.root_name(skeleton, prefix), skeleton, fmt, source, prefix,
            fixed_base, index)))
    return infos


def add_model(engine: DartEngine, model: models.Model) -> list[EntityInfo]:
    """Records for a parsed skeleton's root and links, its joints, and the world."""
    skeleton, root = model.skeleton, model.root
    # The world's own geoms, and a root welded to the world, do not move.
    scenery = skeleton.getName() == models.MJCF_WORLD_BODIES
    static = scenery or skeleton.getRootJoint().getType() == "WeldJoint"
    skeleton.setName(spawning.MODEL + root)
    if scenery:
        skeleton.setMobile(False)
    link_names = [root, *models.link_names(skeleton, model.prefix)[1:]]
    nodes = skeleton.getBodyNodes()
    friction, restitution = engine._values["default_friction"], engine._values[
        "default_restitution"]
    infos = []
    for k, (name, node) in enumerate(zip(link_names, nodes, strict=True)):
        surface = node_surface(node, friction, restitution)
        fixed = static if k == 0 else scenery  # a fixed base's links move
        body = spawning.Body(name, "model" if k == 0 else "link", (), fixed,
                          math.nan if fixed else float(node.getMass()), *surface,
                          False, False, skeleton, node, None, root,
                          link_names[1:] if k == 0 else [])
        engine._bodies[name] = body
        mass = body_properties(engine, body)[0]
        infos.append(EntityInfo(name=name, shape=body.shape, static=fixed,
                                mass=None if math.isnan(mass) else mass,
                                friction=surface[0], restitution=surface[1],
                                source="model", model=root))
    engine._owners.append(root)
    engine._models[root] = model
    links = {model_joints.id_of(node): name
             for name, node in zip(link_names, nodes, strict=True)}
    for joint in model_joints.describe(skeleton, model.prefix, root, links):
        engine._robots.joints[joint.info.name] = joint
    engine._world.addSkeleton(skeleton)
    return infos


def node_surface(node: Any, friction: float, restitution: float) -> tuple[float, float]:
    """A node's friction and restitution: its first shape's that has them, or the
    defaults."""
    for k in range(node.getNumShapeNodes()):
        aspect = node.getShapeNode(k).getDynamicsAspect()
        if aspect is not None:
            return float(aspect.getFrictionCoeff()), float(aspect.getRestitutionCoeff())
    return float(friction), float(restitution)


def edit_model(bodies: dict[str, spawning.Body], root: spawning.Body,
               props: BodyProperties) -> None:
    """A model's root edited whole: its mass scaled over every link, friction and
    restitution on every shape."""
    names = [root.name, *root.links]
    if props.mass is not None:
        scale = float(props.mass) / float(root.skeleton.getMass())
        for name in names:
            node = bodies[name].node
            node.setMass(node.getMass() * scale)
            node.setMomentOfInertia(*_scaled_moment(node, scale))
    for name in names:
        body = bodies[name]
        if props.friction is not None:
            body.friction = float(props.friction)
        if props.restitution is not None:
            body.restitution = float(props.restitution)
        if props.friction is not None or props.restitution is not None:
            spawning.set_surface(body)
        if props.rgba is not None:
            body.rgba = tuple(props.rgba)
    if props.mass is not None:
        root.mass = float(props.mass)


def _scaled_moment(node: Any, scale: float) -> list[float]:
    moment = np.asarray(node.getInertia().getMoment(), dtype=float) * scale
    return [moment[0, 0], moment[1, 1], moment[2, 2], moment[0, 1], moment[0, 2],
            moment[1, 2]]
