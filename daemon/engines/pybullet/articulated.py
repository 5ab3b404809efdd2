"""The PyBullet engine's part that loads models and drives their joints: a model's root and
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

import itertools
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet import models
from galton.daemon.engines.pybullet.bodies import link_masses, load_bodies
from galton.daemon.engines.pybullet.files import facts
from galton.daemon.engines.pybullet.frames import (
    Offset,
    base_offset,
    frame_to_com,
    link_states,
)
from galton.daemon.engines.pybullet.joints import articulation, free_motors
from galton.daemon.engines.pybullet.rebuild import Body, Model
from galton.daemon.engines.pybullet.robots import Robots
from galton.protocol import EntityInfo, JointInfo, NameNotUniqueError, NotFoundError

if TYPE_CHECKING:
    from galton.daemon.engines.pybullet.bodies import BodyMaker


class Articulated:
    """Models, links, joints, targets and wrenches (mixed into PybulletEngine)."""

    _bc: BulletClient
    bodies: dict[str, Body]
    _maker: BodyMaker
    _values: dict[str, Any]
    _batches: itertools.count[int]
    _change: Callable[..., Any]
    robots: Robots
    frames: dict[str, Offset]  # roots whose inertial frame is not their link frame

    if TYPE_CHECKING:
        def _read(self, ids: list[int]) -> tuple[np.ndarray, np.ndarray]: ...
        def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]: ...

    def _uid_of(self, name: str) -> int:
        try:
            return self.bodies[name].uid
        except KeyError:
            raise NotFoundError(f"no entity named {name!r} in the PyBullet world") from None

    # -- loading --------------------------------------------------------------------------
    def _load(self, fmt: str, text: str | None, path: str | None, prefix: str,
              fixed_base: bool) -> list[EntityInfo]:
        """Load, name and register a model; a refused load leaves the world as it was."""
        source = models.model_text(fmt, text, path)
        fixed = fixed_base and fmt == "urdf"
        ids = load_bodies(self._bc, self._maker, fmt, source, path, fixed)
        roots: list[str] = []
        try:
            return self._adopt_model(fmt, ids, prefix, source, path, fixed, roots)
        except BaseException:
            self._maker.remove(ids)
            for name in roots:
                self.bodies.pop(name, None)
                self.frames.pop(name, None)
            self.robots.forget(roots)
            raise

    def _adopt_model(self, fmt: str, ids: list[int], prefix: str, text: str,
                     path: str | None, fixed: bool, roots: list[str]) -> list[EntityInfo]:
        """Name the loaded bodies and their links, refuse names in use, register them
        (appending each root to ``roots`` as it is registered)."""
        taken = set(self.bodies) | set(self.robots.links)
        names = models.body_names(self._bc, fmt, ids, prefix, taken)
        file = facts(fmt, text)
        links = models.link_names(self._bc, ids, names, prefix, taken, file)
        joints = self.robots.joint_names()
        batch, infos = next(self._batches), []
        for index, (uid, name) in enumerate(zip(ids, names, strict=True)):
            floating = self._bc.getDynamicsInfo(uid, -1)[0] > 0 and not fixed
            model = articulation(self._bc, uid, name, links[index], prefix, floating, file)
            used = [j.name for j in model.infos if j.name in joints]
            if used:
                raise NameNotUniqueError(f"the model's joint {used[0]!r} has the name of a "
                                         "loaded joint; load it with another prefix")
            body = self._adopt_model_body(uid, name, batch)
            roots.append(name)
            poses, twists = self._read([uid])
            body.model = Model(fmt, text, path, index,
                               link_masses(self._bc, uid, body.links),
                               (poses[0].tolist(), twists[0].tolist()), fixed_base=fixed)
            self.robots.add(model)
            offset = base_offset(self._bc, uid)
            if offset is not None:
                self.frames[name] = offset
            infos.append(models.entity_info(self._bc, name, body, body.model))
            infos.extend(models.link_info(self._bc, uid, j, link, name)
                         for j, link in enumerate(model.links) if link is not None)
        return infos

    def _adopt_model_body(self, uid: int, name: str, batch: int) -> Body:
        """Register one loaded body (see models.model_body), its joints free."""
        body = models.model_body(self._bc, self._change,
                                 self._values["pybullet.ccd_swept_sphere_radius"], uid, batch)
        free_motors(self._bc, uid)
        self.bodies[name] = body
        return body

    # -- links as entities ----------------------------------------------------------------
    def link_states(self, names: Sequence[str], rows: list[int], poses: np.ndarray,
                     twists: np.ndarray) -> None:
        """Put the frames of these links (at ``rows`` of the arrays): one getLinkStates
        per model."""
        groups: dict[str, tuple[list[int], list[int]]] = {}
        for k in rows:
            root, link = self.robots.links[names[k]]
            group = groups.setdefault(root, ([], []))
            group[0].append(link)
            group[1].append(k)
        for root, (links, order) in groups.items():
            poses[order], twists[order] = link_states(self._bc, self._uid_of(root), links)

    def to_centres(self, names: Sequence[str], poses: np.ndarray | None,
                    twists: np.ndarray | None) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Link-frame states of offset roots as PyBullet's centre-of-mass ones."""
        poses = None if poses is None else np.array(poses, dtype=float)
        twists = None if twists is None else np.array(twists, dtype=float)
        rows = [k for k, name in enumerate(names) if name in self.frames]
        offsets = [self.frames[names[k]] for k in rows]
        turns = poses[rows, 3:] if poses is not None else self.get_states(
            [names[k] for k in rows])[0][:, 3:]
        some_poses = None if poses is None else poses[rows]
        some_twists = None if twists is None else twists[rows]
        frame_to_com(some_poses, some_twists, offsets, turns)
        if poses is not None and some_poses is not None:
            poses[rows] = some_poses
        if twists is not None and some_twists is not None:
            twists[rows] = some_twists
        return poses, twists

    def _link_properties(self, name: str) -> tuple[float, float, float]:
        root, link = self.robots.links[name]
        info = self._bc.getDynamicsInfo(self._uid_of(root), link)
        return float(info[0]), float(info[1]), float(info[5])

    def joints_finite(self) -> bool:
        """Whether every model's joint positions and velocities are finite (a welded
        model's links diverge where no base shows it)."""
        for root, model in self.robots.models.items():
            if model.indices:
                states = self._bc.getJointStates(self._uid_of(root), model.indices)
                if not np.isfinite([value for s in states for value in s[:2]]).all():
                    return False
        return True

    # -- joints ---------------------------------------------------------------------------
    def joints(self) -> list[JointInfo]:
        return self.robots.joints()

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self.robots.read(self._bc, self._uid_of, names)

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        self.robots.write(self._bc, self._uid_of, names, np.asarray(positions, float),
                           None if velocities is None else np.asarray(velocities, float))

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        arrays = (np.asarray(a, float) for a in (targets, kp, kd, max_effort))
        self.robots.hold(names, mode, *arrays)

    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        self.robots.check_entities(self.bodies, names)
        self.robots.hold_wrenches(self._bc, self._uid_of, names, np.asarray(wrenches, float),
                                   None if points is None else np.asarray(points, float))

    def clear_wrenches(self, names: Sequence[str] | None) -> None:
        if names is None:
            self.robots.wrenches.clear()
        for name in names or ():
            self.robots.wrenches.pop(name, None)

    def restore_joints(self) -> None:
        self.robots.restore(self._bc, self._uid_of)
