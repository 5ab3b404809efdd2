"""The PyBullet engine's models and joints, functions of the engine: a model's root and
links as entities, its joints, targets and held wrenches (records in robots.py,
the actuator law in joints.py, link frames in frames.py).

A URDF model is one multibody: its base is the root entity, every other link a link
entity, under the link names of the file. An MJCF file gives one multibody per top-level
body (and one for the world's own geoms, named after PyBullet's name for it); PyBullet's
MJCF importer turns each joint into a link of its own (``link<i>_<j>``) and welds the
file's body to it (``jointfix_<i>_<j>``): those are hidden, and the file's bodies and
joints listed (files.py). A top-level MJCF body with a joint that is not free
has such a link as PyBullet's base: that root entity keeps PyBullet's name.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.pybullet import models
from galton.daemon.engines.pybullet.bodies import link_masses, load_bodies
from galton.daemon.engines.pybullet.files import facts
from galton.daemon.engines.pybullet.frames import (
    base_offset,
    frame_to_com,
    link_states,
)
from galton.daemon.engines.pybullet.joints import articulation, free_motors
from galton.daemon.engines.pybullet.rebuild import Body, Model
from galton.protocol import EntityInfo, JointInfo, NameNotUniqueError

if TYPE_CHECKING:
    from galton.daemon.engines.pybullet.engine import PybulletEngine


def load(engine: PybulletEngine, fmt: str, text: str | None, path: str | None, prefix: str,
         fixed_base: bool) -> list[EntityInfo]:
    """Load, name and register a model; a refused load leaves the world as it was."""
    source = models.model_text(fmt, text, path)
    fixed = fixed_base and fmt == "urdf"
    ids = load_bodies(engine._bc, engine._maker, fmt, source, path, fixed)
    roots: list[str] = []
    try:
        return adopt_model(engine, fmt, ids, prefix, source, path, fixed, roots)
    except BaseException:
        engine._maker.remove(ids)
        for name in roots:
            engine.bodies.pop(name, None)
            engine.frames.pop(name, None)
        engine.robots.forget(roots)
        raise


def adopt_model(engine: PybulletEngine, fmt: str, ids: list[int], prefix: str, text: str,
                path: str | None, fixed: bool, roots: list[str]) -> list[EntityInfo]:
    """Name the loaded bodies and their links, refuse names in use, register them
    (appending each root to ``roots`` as it is registered)."""
    taken = set(engine.bodies) | set(engine.robots.links)
    names = models.body_names(engine._bc, fmt, ids, prefix, taken)
    file = facts(fmt, text)
    links = models.link_names(engine._bc, ids, names, prefix, taken, file)
    joints = engine.robots.joint_names()
    batch, infos = next(engine._batches), []
    for index, (uid, name) in enumerate(zip(ids, names, strict=True)):
        floating = engine._bc.getDynamicsInfo(uid, -1)[0] > 0 and not fixed
        model = articulation(engine._bc, uid, name, links[index], prefix, floating, file)
        used = [j.name for j in model.infos if j.name in joints]
        if used:
            raise NameNotUniqueError(f"the model's joint {used[0]!r} has the name of a "
                                     "loaded joint; load it with another prefix")
        body = adopt_model_body(engine, uid, name, batch)
        roots.append(name)
        poses, twists = engine._read([uid])
        body.model = Model(fmt, text, path, index,
                           link_masses(engine._bc, uid, body.links),
                           (poses[0].tolist(), twists[0].tolist()), fixed_base=fixed)
        engine.robots.add(model)
        offset = base_offset(engine._bc, uid)
        if offset is not None:
            engine.frames[name] = offset
        infos.append(models.entity_info(engine._bc, name, body, body.model))
        infos.extend(models.link_info(engine._bc, uid, j, link, name)
                     for j, link in enumerate(model.links) if link is not None)
    return infos


def adopt_model_body(engine: PybulletEngine, uid: int, name: str, batch: int) -> Body:
    """Register one loaded body (see models.model_body), its joints free."""
    body = models.model_body(engine._bc, engine._change,
                             engine._values["pybullet.ccd_swept_sphere_radius"], uid, batch)
    free_motors(engine._bc, uid)
    engine.bodies[name] = body
    return body

def put_link_states(engine: PybulletEngine, names: Sequence[str], rows: list[int],
                    poses: np.ndarray, twists: np.ndarray) -> None:
    """Put the frames of these links (at ``rows`` of the arrays): one getLinkStates
    per model."""
    groups: dict[str, tuple[list[int], list[int]]] = {}
    for k in rows:
        root, link = engine.robots.links[names[k]]
        group = groups.setdefault(root, ([], []))
        group[0].append(link)
        group[1].append(k)
    for root, (links, order) in groups.items():
        poses[order], twists[order] = link_states(engine._bc, engine._uid_of(root), links)


def to_centres(engine: PybulletEngine, names: Sequence[str], poses: np.ndarray | None,
               twists: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Link-frame states of offset roots as PyBullet's centre-of-mass ones."""
    poses = None if poses is None else np.array(poses, dtype=float)
    twists = None if twists is None else np.array(twists, dtype=float)
    rows = [k for k, name in enumerate(names) if name in engine.frames]
    offsets = [engine.frames[names[k]] for k in rows]
    turns = poses[rows, 3:] if poses is not None else engine.get_states(
        [names[k] for k in rows])[0][:, 3:]
    some_poses = None if poses is None else poses[rows]
    some_twists = None if twists is None else twists[rows]
    frame_to_com(some_poses, some_twists, offsets, turns)
    if poses is not None and some_poses is not None:
        poses[rows] = some_poses
    if twists is not None and some_twists is not None:
        twists[rows] = some_twists
    return poses, twists


def link_properties(engine: PybulletEngine, name: str) -> tuple[float, float, float]:
    root, link = engine.robots.links[name]
    info = engine._bc.getDynamicsInfo(engine._uid_of(root), link)
    return float(info[0]), float(info[1]), float(info[5])


def joints_finite(engine: PybulletEngine) -> bool:
    """Whether every model's joint positions and velocities are finite (a welded
    model's links diverge where no base shows it)."""
    for root, model in engine.robots.models.items():
        if model.indices:
            states = engine._bc.getJointStates(engine._uid_of(root), model.indices)
            if not np.isfinite([value for s in states for value in s[:2]]).all():
                return False
    return True

def joints(engine: PybulletEngine) -> list[JointInfo]:
    return engine.robots.joints()


def get_joint_states(engine: PybulletEngine, names: Sequence[str]
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return engine.robots.read(engine._bc, engine._uid_of, names)


def set_joint_states(engine: PybulletEngine, names: Sequence[str], positions: np.ndarray,
                     velocities: np.ndarray | None) -> None:
    engine.robots.write(engine._bc, engine._uid_of, names, np.asarray(positions, float),
                       None if velocities is None else np.asarray(velocities, float))


def set_joint_targets(engine: PybulletEngine, names: Sequence[str], mode: str, targets: np.ndarray,
                      kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
    arrays = (np.asarray(a, float) for a in (targets, kp, kd, max_effort))
    engine.robots.hold(names, mode, *arrays)


def set_wrenches(engine: PybulletEngine, names: Sequence[str], wrenches: np.ndarray,
                 points: np.ndarray | None) -> None:
    engine.robots.check_entities(engine.bodies, names)
    engine.robots.hold_wrenches(engine._bc, engine._uid_of, names, np.asarray(wrenches, float),
                               None if points is None else np.asarray(points, float))


def clear_wrenches(engine: PybulletEngine, names: Sequence[str] | None) -> None:
    if names is None:
        engine.robots.wrenches.clear()
    for name in names or ():
        engine.robots.wrenches.pop(name, None)


def restore_joints(engine: PybulletEngine) -> None:
    engine.robots.restore(engine._bc, engine._uid_of)
