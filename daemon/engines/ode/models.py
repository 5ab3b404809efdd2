"""URDF robots into ODE: ``yourdfpy`` reads the file, each link with mass becomes an ODE body
at its centre of mass (ODE wants the body's origin there) carrying its collision geoms, and
each joint an ODE joint (joints.py). MJCF is not offered: ODE has no loader for it.

Collision shapes: box, sphere and cylinder as ODE's own; a mesh as the box of its bounds
(shapes.py). Links of one model do not collide with each other (contacts.py).
A link without inertial gets 1 g and a 1e-6 kg·m² inertia, as such a link must move with
its joint. The root sits at the world's origin, a kinematic body (held still, moved only by
teleports) unless ``fixed_base`` is False, when it is free and its free joint is listed.
"""

from __future__ import annotations

import ctypes
import io
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from galton.daemon.engines.ode import frames
from galton.daemon.engines.ode.joints import HI_STOP, HINGES, LO_STOP, Joint, Model, Robots
from galton.daemon.engines.ode.native import LIB, Mass, body_state, quaternion
from galton.daemon.engines.ode.shapes import link_shapes
from galton.daemon.engines.ode.spawn import AWAKE, Body, make_geom
from galton.protocol import EntityInfo, InvalidArgumentError, JointInfo, NameNotUniqueError
from galton.protocol.vocabulary import MAX_MASS, MIN_INERTIA, MIN_MASS

MODEL_FORMATS = ("urdf",)
MASSLESS = 1e-3  # kg of a link that gives no inertial
JOINT_TYPES = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
               "fixed": "fixed"}


def parse(text: str | None, path: str | None) -> Any:
    """The URDF's robot (yourdfpy), or InvalidArgumentError saying why not."""
    import yourdfpy  # only when a model is loaded: it pulls in trimesh
    from lxml import etree

    if text is None and path is None:
        raise InvalidArgumentError("give a model as text or as a path")
    if text is None and not os.path.isfile(path or ""):
        raise InvalidArgumentError(f"no model file at {path!r}")
    try:
        data = text.encode() if text is not None else Path(path or "").read_bytes()
        etree.fromstring(data)  # strict: yourdfpy would recover what it can of a broken file
        urdf = yourdfpy.URDF.load(io.BytesIO(data) if text is not None else path,
                                  build_scene_graph=False, load_meshes=False,
                                  load_collision_meshes=False)
    except Exception as exc:  # lxml's and yourdfpy's errors alike: the file is bad
        raise InvalidArgumentError(f"the URDF model does not parse: {exc}") from exc
    robot = urdf.robot
    if not robot.links:
        raise InvalidArgumentError("the URDF model holds no links")
    return robot


def _root(robot: Any) -> str:
    children = {j.child for j in robot.joints}
    roots = [link.name for link in robot.links if link.name not in children]
    if len(roots) != 1:
        raise InvalidArgumentError(f"a URDF model needs one root link; this one has {roots}")
    return str(roots[0])


def _ordered(robot: Any, root: str) -> list[Any]:
    """The joints, each after the joint that places its parent."""
    placed, ordered, left = {root}, [], list(robot.joints)
    while left:
        ready = [j for j in left if j.parent in placed]
        if not ready:
            raise InvalidArgumentError("the URDF's joints do not form a tree from its root")
        for joint in ready:
            ordered.append(joint)
            placed.add(joint.child)
            left.remove(joint)
    return ordered


def _check_inertial(link: str, mass: float, inertia: np.ndarray) -> None:
    """Refuse a link ODE would abort on (dMassCheck), or whose push by a bounded effort
    would make ODE's quaternion infinite (issue 46): its mass within the protocol's
    [MIN_MASS, MAX_MASS], its inertia finite, symmetric-positive, each principal moment at
    least MIN_INERTIA."""
    if not (math.isfinite(mass) and MIN_MASS <= mass <= MAX_MASS):
        raise InvalidArgumentError(
            f"link {link!r}: mass {mass:g} kg is outside the protocol's [{MIN_MASS:g}, "
            f"{MAX_MASS:g}] kg (docs/protocol.md, \"Bounds\")")
    if not np.isfinite(inertia).all() or (np.abs(inertia) > MAX_MASS).any():
        raise InvalidArgumentError(f"link {link!r}: its inertia must be finite numbers "
                                   f"within {MAX_MASS:g} kg m²")
    moments = np.linalg.eigvalsh((inertia + inertia.T) / 2)
    if moments.min() < MIN_INERTIA:
        raise InvalidArgumentError(
            f"link {link!r}: its inertia's smallest principal moment is {moments.min():g} "
            f"kg m², under the protocol's {MIN_INERTIA:g} (docs/protocol.md, \"Bounds\")")


def _mass(link: Any) -> tuple[float, Mass, frames.Frame]:
    """The link's mass, ODE mass about its centre, and the centre's frame in the link."""
    mass = Mass()
    inertial = link.inertial
    if inertial is None or inertial.mass is None or inertial.mass <= 0:
        LIB.dMassSetParameters(ctypes.addressof(mass), MASSLESS, 0, 0, 0, 1e-6, 1e-6, 1e-6,
                               0, 0, 0)
        return MASSLESS, mass, frames.IDENTITY
    origin = frames.IDENTITY if inertial.origin is None else frames.from_matrix(
        np.asarray(inertial.origin, dtype=float))
    i = np.asarray(inertial.inertia if inertial.inertia is not None else np.eye(3) * 1e-6,
                   dtype=float)
    _check_inertial(link.name, float(inertial.mass), i)
    LIB.dMassSetParameters(ctypes.addressof(mass), float(inertial.mass), 0, 0, 0, i[0, 0],
                           i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2])
    return float(inertial.mass), mass, origin


def load_urdf(world: int, space: int, robots: Robots, text: str | None, path: str | None,
              prefix: str, fixed_base: bool, values: dict[str, Any], taken: set[str]
              ) -> tuple[list[Body], list[EntityInfo]]:
    robot = parse(text, path)
    root = _root(robot)
    ordered = _ordered(robot, root)
    links = [root] + [j.child for j in ordered]
    names = {name: prefix + name for name in links}
    in_use = [n for n in names.values() if n in taken or n in robots.links]
    if in_use:
        raise NameNotUniqueError(f"the model's link {in_use[0]!r} has the name of an existing "
                                 "entity; load it with another prefix")
    by_name = {link.name: link for link in robot.links}
    shapes = {name: link_shapes(by_name[name]) for name in links}  # every refusal before a body
    made: list[Body] = []
    try:
        placed = {root: frames.IDENTITY}
        for joint in ordered:
            placed[joint.child] = frames.compose(placed[joint.parent], _origin(joint))
        for name in links:
            made.append(_link_body(world, space, by_name[name], names[name], names[root],
                                   placed[name], shapes[name], values, name == root))
        bodies = {b.name: b for b in made}
        model = Model(names[root], [names[n] for n in links], [], source={
            "text": text, "path": path, "prefix": prefix, "fixed_base": fixed_base})
        if fixed_base:  # a kinematic body: immovable by any force, moved by teleports
            LIB.dBodySetKinematic(bodies[names[root]].body)
            bodies[names[root]].welded = True
        else:
            model.free = JointInfo(name=names[root] + ":free", model=names[root], type="free",
                                   parent="", child=names[root])
        for joint in ordered:
            model.joints.append(_joint(world, joint, prefix, names, bodies, placed))
    except BaseException:
        from galton.daemon.engines.ode.spawn import destroy
        destroy(made)
        raise
    robots.add(model)
    infos = [EntityInfo(name=b.name, shape="model" if b.name == names[root] else "link",
                        static=b.welded, mass=b.mass, friction=b.friction,
                        restitution=b.restitution, source="model", model=names[root])
             for b in made]
    infos[0].mass = float(sum(b.mass for b in made))
    return made, infos


def _origin(joint: Any) -> frames.Frame:
    return frames.from_matrix(np.asarray(joint.origin if joint.origin is not None
                                         else np.eye(4), dtype=float))


def _link_body(world: int, space: int, link: Any, name: str, root: str,
               placed: frames.Frame, shapes: list[tuple[str, tuple[float, ...], frames.Frame]],
               values: dict[str, Any], is_root: bool) -> Body:
    total, mass, centre = _mass(link)
    body = Body(name, "model" if is_root else "link", (), False, 0, int(LIB.dBodyCreate(world)),
                total, values["default_friction"], values["default_restitution"], True, True,
                None, [], model=root, frame=centre)
    LIB.dBodySetMass(body.body, ctypes.addressof(mass))
    at = frames.compose(placed, centre)
    LIB.dBodySetPosition(body.body, *at[0].tolist())
    LIB.dBodySetQuaternion(body.body, quaternion(at[1]))
    body.state = np.ctypeslib.as_array(body_state(body.body))
    for shape, size, where in shapes:
        body.link_shapes.append((shape, size, (*map(float, where[0]), *map(float, where[1]))))
        geom = make_geom(space, shape, size)
        LIB.dGeomSetBody(geom, body.body)
        offset = frames.compose(frames.inverse(centre), where)
        LIB.dGeomSetOffsetPosition(geom, *offset[0].tolist())
        LIB.dGeomSetOffsetQuaternion(geom, quaternion(offset[1]))
        if body.geom:
            body.extra.append(geom)
        else:
            body.geom = geom
    body.set_bits(AWAKE)
    return body


def _joint(world: int, joint: Any, prefix: str, names: dict[str, str], bodies: dict[str, Body],
           placed: dict[str, frames.Frame]) -> Joint:
    kind = JOINT_TYPES.get(joint.type)
    if kind is None:
        raise InvalidArgumentError(f"the ode engine does not load {joint.type} joints "
                                   f"({joint.name!r})")
    axis = np.asarray(joint.axis if joint.axis is not None else [1.0, 0, 0], dtype=float)
    axis = axis / (np.linalg.norm(axis) or 1.0)
    limit, dynamics = joint.limit, joint.dynamics
    limited = joint.type in ("revolute", "prismatic") and limit is not None and \
        limit.lower is not None and limit.upper is not None
    info = JointInfo(
        name=prefix + joint.name, model=bodies[
            names[joint.child]].model or "", type=kind, parent=names[joint.parent],
        child=names[joint.child], axis=tuple(axis.tolist()) if kind != "fixed" else
        (0.0, 0.0, 0.0), lower=float(limit.lower) if limited else None,
        upper=float(limit.upper) if limited else None,
        damping=float(dynamics.damping or 0.0) if dynamics is not None else 0.0,
        effort_limit=None if limit is None or limit.effort is None else float(limit.effort),
        velocity_limit=None if limit is None or limit.velocity is None else float(
            limit.velocity))
    child, parent = bodies[names[joint.child]].body, bodies[names[joint.parent]].body
    frame = placed[joint.child]
    world_axis = frames.rotate(frame[1], axis)
    if joint.type in HINGES:
        handle = int(LIB.dJointCreateHinge(world, None))
        LIB.dJointAttach(handle, child, parent)
        LIB.dJointSetHingeAnchor(handle, *frame[0].tolist())
        LIB.dJointSetHingeAxis(handle, *world_axis.tolist())
        _stops(handle, LIB.dJointSetHingeParam, info)
    elif joint.type == "prismatic":
        handle = int(LIB.dJointCreateSlider(world, None))
        LIB.dJointAttach(handle, child, parent)
        LIB.dJointSetSliderAxis(handle, *world_axis.tolist())
        _stops(handle, LIB.dJointSetSliderParam, info)
    else:
        handle = int(LIB.dJointCreateFixed(world, None))
        LIB.dJointAttach(handle, child, parent)
        LIB.dJointSetFixed(handle)
    return Joint(info, handle, _origin(joint), axis)


def _stops(handle: int, set_param: Any, info: JointInfo) -> None:
    if info.lower is not None and info.upper is not None and math.isfinite(info.lower):
        set_param(handle, LO_STOP, info.lower)
        set_param(handle, HI_STOP, info.upper)
