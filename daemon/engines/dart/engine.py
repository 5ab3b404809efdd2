"""The DART engine, set up as Gazebo Harmonic runs it through gz-physics' dartsim plugin:
DART's world with ODE's collision detector, a 1 ms step, SDF's surface defaults
(friction 1, restitution 0). docs/ENGINES.md names the gz-physics file behind each setting.

What differs from Gazebo, and why: gz-physics raises DART's contact limit per step to
10,000 and caps each pair at SDF's ``max_contacts`` (20); dartpy hands out only a copy of
the constraint solver's collision option, so this engine runs DART's own limit (1,000
contacts a step, shared between colliding pairs) and no per-pair cap. Past 1,000
touching pairs the pairs found last get no contact (DART warns once).

The class is the Engine contract, each method short or a call to the module of its
part: spawn.py (records, spawned skeletons, the world's set-up), state.py
(states and divergence), models.py (URDF and MJCF), joints.py (joints, targets, wrenches),
snapshot/ (snapshots), rebuild.py (records, rebuilds), meshes.py (mesh shapes), shapes.py
and contacts.py. dartpy has no ray casts and no headless renderer: ``raycast`` and
``render`` are FEATURE_UNSUPPORTED (rays.py and render.py say so).
"""

from __future__ import annotations

import dataclasses
import importlib.metadata
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from galton.daemon.engines.base import (
    ContactPoints,
    Engine,
    Shape,
    ShapeMesh,
    Target,
)
from galton.daemon.engines.dart import contacts as contact_points
from galton.daemon.engines.dart import fast_state, frames, meshes, models, rebuild, state
from galton.daemon.engines.dart import snapshot as snapshots
from galton.daemon.engines.dart import spawn as spawning
from galton.daemon.engines.dart.joints import Robots
from galton.daemon.engines.dart.mesh_files import MeshFiles
from galton.daemon.engines.dart.models import MODEL_FORMATS
from galton.daemon.engines.dart.params import PARAMS
from galton.daemon.engines.dart.shapes import node_meshes, node_shapes
from galton.daemon.engines.geometry import check_group
from galton.daemon.engines.params import check_updates
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    EntityInfo,
    InvalidArgumentError,
    JointInfo,
)
from galton.protocol.vocabulary import POSE_WIDTH, TWIST_WIDTH


class DartEngine(Engine):
    """Named rigid bodies and models in a DART world."""

    name = "dart"
    param_specs = PARAMS
    model_formats = MODEL_FORMATS
    spawn_inertia = True
    # The records a rebuild makes the world again from (rebuild.py: init_records).
    _owners: list[str]  # spawned bodies and model roots, in the order they were made
    _models: dict[str, models.Model]
    _edits: dict[str, list[tuple[str, BodyProperties]]]  # per model root, in order
    _loaded_meshes: dict[tuple[bytes, bytes], Any]  # during a restore: mesh -> its shape

    def __init__(self) -> None:
        self._values: dict[str, Any] = spawning.defaults()
        self._world = spawning.new_world(self._values)
        self._bodies: dict[str, spawning.Body] = {}
        self._robots = Robots()
        self._mesh_files = MeshFiles()  # model mesh files' triangles, for get_shapes
        rebuild.init_records(self)
        self._unchecked = False  # states were set from outside since the last step
        self._diverged = False

    # -- records (rebuild.py) -------------------------------------------------------------
    # What snapshot/ and fast_state.py call on the engine, each a call to rebuild.py.
    def _lookup(self, names: Sequence[str]) -> list[spawning.Body]:
        return rebuild.lookup(self, names)

    def _check_new(self, names: Sequence[str]) -> None:
        rebuild.check_new(self, names)

    def _add(self, body: spawning.Body) -> None:
        rebuild.add(self, body)

    def _add_model(self, model: models.Model) -> list[EntityInfo]:
        return rebuild.add_model(self, model)

    def _edit(self, body: spawning.Body, props: BodyProperties) -> None:
        rebuild.edit(self, body, props)

    def _rebuild(self) -> None:
        rebuild.rebuild(self)

    # -- description ----------------------------------------------------------------------
    @classmethod
    def engine_version(cls) -> str:
        return importlib.metadata.version("dartpy")

    @property
    def timestep(self) -> float:
        return float(self._values["timestep"])

    def get_params(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._values.items()}

    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, PARAMS, params)
        self._values.update(clean)
        spawning.configure(self._world, self._values)
        rebuild.follow_defaults(self, clean)

    # -- bodies ---------------------------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        self._check_new([n for g in groups for n in g.names])
        for group in groups:
            check_group(group)
        for group in groups:
            if group.names:
                self._spawn_group(group)

    def _spawn_group(self, group: BodyGroup) -> None:
        mass, friction, restitution = spawning.group_values(group, self._values)
        size = tuple(float(s) for s in group.size)
        poses = np.asarray(group.poses, dtype=float).reshape(-1, POSE_WIDTH)
        twists = np.zeros((len(poses), TWIST_WIDTH)) if group.twists is None else (
            np.asarray(group.twists, dtype=float).reshape(-1, TWIST_WIDTH))
        positions = frames.poses_to_free(poses)
        velocities = frames.twists_to_free(twists)
        if group.static:
            velocities[:] = 0.0
        mesh = None if group.vertices is None or group.faces is None else (
            group.vertices, group.faces)
        shared = None if mesh is None else meshes.mesh_shape(*mesh)
        for k, name in enumerate(group.names):
            body = spawning.Body(name, group.shape, size, group.static, mass, friction,
                              restitution, group.friction is None, group.restitution is None,
                              None, None, group.rgba, unit_inertia=None if group.inertia is None
                              else tuple(i / mass for i in group.inertia),
                              mesh=mesh, mesh_shape=shared)
            spawning.build(body, positions[k], velocities[k])
            self._add(body)

    def delete(self, names: Sequence[str]) -> None:
        found = self._lookup(names)
        for body in found:
            rebuild.remove(self, body)

    def clear(self) -> None:
        self._world = spawning.new_world(self._values)
        self._bodies.clear()
        self._robots = Robots()
        rebuild.init_records(self)
        self._diverged = False

    def reset_dynamics(self) -> None:
        """A new world holding the same skeletons, in the order they were made: the
        collision detector's spaces start afresh, so a rewound world replays its first run."""
        self._rebuild()
        self._diverged = False
        self._unchecked = True

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        found = self._lookup(names)
        if props.mass is not None:
            static = [b.name for b in found if b.static]
            if static:
                raise InvalidArgumentError(f"entity {static[0]!r} is static: it has no mass")
        for body in found:
            self._edit(body, props)

    def properties(self, names: Sequence[str]) -> np.ndarray:
        rows = [rebuild.body_properties(self, body) for body in self._lookup(names)]
        return np.array(rows, dtype=float).reshape(len(rows), 3)

    # -- states ---------------------------------------------------------------------------
    def shapes(self, names: Sequence[str]) -> list[list[Shape]]:
        return [node_shapes(body.node) for body in self._lookup(names)]

    def shape_meshes(self, names: Sequence[str]) -> list[dict[int, ShapeMesh]]:
        """The triangles DART collides model mesh links with (mesh_files.py)."""
        return [node_meshes(body.node, self._mesh_files) for body in self._lookup(names)]

    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        return state.read(self._lookup(names))

    def pose_reader(self, names: Sequence[str]) -> Callable[[], np.ndarray]:
        """Poses without velocities; the names looked up on each read (50 µs for 1,000),
        so a removed body is never read."""
        fixed = list(names)
        return lambda: state.read_poses(self._lookup(fixed))

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        state.write(self._lookup(names), poses, twists)
        self._unchecked = True

    def step(self, count: int) -> None:
        """World.step, after each held target and wrench is applied where any are (DART
        clears forces after every step). States set from outside are checked first: ODE
        aborts the process on a NaN or far-off body, so such a world is not stepped."""
        if self._unchecked:
            self._unchecked = False
            if not state.safe_to_step(list(self._bodies.values())):
                self._diverged = True
        if self._diverged:
            return
        world, robots = self._world, self._robots
        robots.sync_damping()
        if robots.busy():
            for _ in range(count):
                robots.actuate()
                world.step()
            return
        for _ in range(count):
            world.step()

    def state_within(self, max_position: float, max_speed: float) -> bool:
        return not self._diverged and state.within(list(self._bodies.values()),
                                                   max_position, max_speed)

    # -- models and joints ----------------------------------------------------------------
    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str, *, fixed_base: bool = True) -> list[EntityInfo]:
        return rebuild.load(self, fmt, text, path, prefix, fixed_base)

    def joints(self) -> list[JointInfo]:
        targets = self._robots.targets
        return [dataclasses.replace(joint.info, mode=targets[name].mode if name in targets
                                    else "none")
                for name, joint in self._robots.joints.items()]

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        found = self._robots.scalar(names)
        positions = np.array([j.joint.getPosition(0) for j in found], dtype=float)
        velocities = np.array([j.joint.getVelocity(0) for j in found], dtype=float)
        efforts = np.array([self._robots.effort(n) for n in names], dtype=float)
        return positions, velocities, efforts

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        found = self._robots.scalar(names)
        for k, joint in enumerate(found):
            joint.joint.setPosition(0, float(positions[k]))
            if velocities is not None:
                joint.joint.setVelocity(0, float(velocities[k]))
        self._unchecked = True

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        self._robots.scalar(names)
        for k, name in enumerate(names):
            if mode == "none":
                self._robots.targets.pop(name, None)
                self._robots.efforts.pop(name, None)
            else:
                self._robots.targets[name] = Target(mode, float(targets[k]), float(kp[k]),
                                                    float(kd[k]), float(max_effort[k]))

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        self._robots.set_damping(names, damping)

    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        found = self._lookup(names)
        for k, body in enumerate(found):
            force = np.asarray(wrenches[k, :3], dtype=float).copy()
            torque = np.asarray(wrenches[k, 3:], dtype=float).copy()
            if points is not None:
                centre = np.asarray(body.node.getCOM(), dtype=float)
                torque = torque + np.cross(np.asarray(points[k], dtype=float) - centre, force)
            self._robots.wrenches[body.name] = (body.node, force, torque)

    def clear_wrenches(self, names: Sequence[str] | None) -> None:
        if names is None:
            self._robots.wrenches.clear()
            return
        for name in names:
            self._robots.wrenches.pop(name, None)

    # -- snapshots (snapshot/, fast_state.py) -----------------------------------------------
    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        return snapshots.snapshot(self, canonical=canonical)

    def restore(self, data: dict[str, Any]) -> None:
        snapshots.restore(self, data)

    def save_state(self) -> object | None:
        """Skeletons' positions and velocities, the time and the held records (fast_state)."""
        return fast_state.save(self)

    def load_state(self, state: object) -> bool:
        return fast_state.load(self, state)

    def restore_joints(self) -> None:
        for joint in self._robots.joints.values():
            if joint.info.type != "free":
                joint.joint.setPositions(np.asarray(joint.loaded, dtype=float))
                joint.joint.setVelocities(np.zeros(len(joint.loaded)))
        self._robots.targets.clear()
        self._robots.efforts.clear()
        self._robots.wrenches.clear()

    # -- perception -----------------------------------------------------------------------
    def contacts(self, names: Sequence[str] | None
                 ) -> ContactPoints:
        return ContactPoints(*contact_points.contacts(
            self._world, rebuild.entity_keys(self), None if names is None else set(names)))
