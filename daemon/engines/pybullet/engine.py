"""The PyBullet engine: a headless Bullet world, one per BulletClient (several can live in
one process, as during an engine switch).

Spawned bodies are plain rigid bodies (``useMaximalCoordinates``): Bullet's continuous
collision detection works only for those, they carry no default damping (a one-link
multibody has 0.04, which slows a free fall by 7 % in one second), and they step and read
faster. Loaded models are multibodies (their joints need it), with damping set to zero.

Contacts: PyBullet multiplies the two bodies' values at a contact, for friction and for
restitution alike, so a body with restitution 0.9 bounces off a body with restitution 0
hardly at all. Restitution is also zero below ``pybullet.restitution_velocity_threshold``.
The contact defaults are PyBullet's own (restitution 0, friction 0.5, contacts from 0.02 m,
cone friction); the Galton board brings its calibrated materials (restitution 0.8275 on
every body, contacts from 0.01 m, pyramid friction: docs/physics/pybullet.md). The solver's
10 iterations are the daemon's (PyBullet: 50). ``contactBreakingThreshold`` is a global of
the PyBullet module: every engine sets its own value when it starts, and the last
``set_params`` wins for all engines of the process.

Memory: removeBody keeps about 0.9 kB per body even with shared collision shapes; only
resetSimulation frees it, which ``clear`` does, and ``delete`` does when the world empties
or, past a count of removed bodies, by rebuilding the world (rebuild.py). Visual
meshes are made once per process (meshes.shared_mesh): createVisualShape never
lets go of the lists it is given.

Rewinding: ``reset_dynamics`` rebuilds the world too, every body made again as it was first
made, so that a stopped world replays its first run bit for bit (Bullet would otherwise keep
contact points and their warm starts across the teleport).

The class is the Engine contract, each method short or a call to the module of its part,
a function of the engine: parameters (params.py), rebuilds (rebuild.py), models, joints,
targets and wrenches (articulated.py), snapshots (snapshot/), render, raycast and contacts
(perception.py), states and the divergence check (state.py), a spawn group's values and
records (spawn.py), a body's updates and properties (props.py), a model load's checks and
names (models.py).
"""

from __future__ import annotations

import importlib.metadata
import itertools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.base import (
    CameraView,
    ContactPoints,
    Engine,
    RayHits,
    Shape,
    ShapeMesh,
    native_output_silenced,
)
from galton.daemon.engines.geometry import check_group
from galton.daemon.engines.params import check_updates
from galton.daemon.engines.pybullet import articulated, perception, rebuild, shapes
from galton.daemon.engines.pybullet import params as parameters
from galton.daemon.engines.pybullet import props as bodyprops
from galton.daemon.engines.pybullet import snapshot as snapshots
from galton.daemon.engines.pybullet import spawn as spawning
from galton.daemon.engines.pybullet import state as states
from galton.daemon.engines.pybullet.bodies import BodyMaker, ShapeCache
from galton.daemon.engines.pybullet.calls import engine_call
from galton.daemon.engines.pybullet.frames import Offset
from galton.daemon.engines.pybullet.joints import set_damping
from galton.daemon.engines.pybullet.mesh_files import HullCache
from galton.daemon.engines.pybullet.models import MODEL_FORMATS
from galton.daemon.engines.pybullet.params import PARAMS
from galton.daemon.engines.pybullet.rebuild import Body as _Body
from galton.daemon.engines.pybullet.render import RENDER_BACKEND
from galton.daemon.engines.pybullet.robots import Robots
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    EntityInfo,
    InvalidArgumentError,
    JointInfo,
    NameNotUniqueError,
    NotFoundError,
)
from galton.protocol.vocabulary import POSE_WIDTH, TWIST_WIDTH


class PybulletEngine(Engine):
    """Named rigid bodies in a headless PyBullet world."""

    name = "pybullet"
    param_specs = PARAMS
    model_formats = MODEL_FORMATS
    spawn_inertia = True

    def __init__(self) -> None:
        with native_output_silenced():  # "argv[0]=" when it connects
            self._bc = BulletClient(connection_mode=pybullet.DIRECT)
        self._closed = False
        bc = self._bc
        # Bound once: BulletClient builds a new functools.partial on every attribute access.
        self.get_pose = bc.getBasePositionAndOrientation
        self.get_velocity = bc.getBaseVelocity
        self.reset_pose = bc.resetBasePositionAndOrientation
        self.reset_velocity = bc.resetBaseVelocity
        self._change = bc.changeDynamics
        self._step = bc.stepSimulation
        self._shapes = ShapeCache(bc)
        self._hulls = HullCache()  # model mesh files' hulls, for get_shapes
        self.bodies: dict[str, _Body] = {}
        self._maker = BodyMaker(bc)
        self._values: dict[str, Any] = {name: spec.default for name, spec in PARAMS.items()}
        self._removed = 0  # bodies removed since resetSimulation last ran
        self.held: dict[str, rebuild.Held] = {}  # states a rebuild could not set bit for bit
        # Poses given to PyBullet (spawn, set_states) since the last step: a rebuild sets
        # them again as given, which reading them back (a rotation matrix) cannot promise.
        self.given: dict[str, list[float]] = {}
        self._batches = itertools.count()  # spawn groups and model loads, in order
        self.robots = Robots()  # models' links, joints, targets, held wrenches
        self.frames: dict[str, Offset] = {}  # roots whose inertial frame is offset
        self.rebuilds = 0
        parameters.configure_world(self)

    # -- description ----------------------------------------------------------------------
    @classmethod
    def engine_version(cls) -> str:
        return importlib.metadata.version("pybullet")

    def render_backend(self) -> str:
        return RENDER_BACKEND

    @property
    def timestep(self) -> float:
        return float(self._values["timestep"])

    # -- parameters -----------------------------------------------------------------------
    def get_params(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._values.items()}

    @engine_call
    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, PARAMS, params)
        self._values.update(clean)
        parameters.apply(self, clean)

    # -- bodies ---------------------------------------------------------------------------
    @engine_call
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        taken = [n for g in groups for n in g.names if n in self.bodies]
        if taken:
            raise NameNotUniqueError(f"an entity named {taken[0]!r} already exists")
        made: list[int] = []
        bodies: dict[str, _Body] = {}
        try:
            for group in groups:
                if group.names:
                    bodies.update(self._spawn_group(group, made, next(self._batches)))
        except BaseException:
            self._maker.remove(made)
            raise
        self.bodies.update(bodies)
        for group in groups:
            self.given.update(zip(group.names, np.asarray(
                group.poses, dtype=float).reshape(-1, POSE_WIDTH).tolist(), strict=True))

    def _spawn_group(self, group: BodyGroup, made: list[int], batch: int,
                     redo: rebuild.Redo | None = None) -> dict[str, _Body]:
        """The group's bodies in (at most) one createMultiBody call, all turned like the
        first, then each one's own orientation where it differs, velocity and dynamics. A
        rebuild (``redo``) makes them as they were first made."""
        check_group(group)
        size = tuple(float(s) for s in group.size)
        poses = np.asarray(group.poses, dtype=float).reshape(-1, POSE_WIDTH).tolist()
        if redo is None:
            redo = spawning.first_redo(poses)
        mass = spawning.group_mass(group, size)
        ids = self._maker.create(mass, *self._group_shapes(group, size),
                                 [pose[:3] for pose in poses], list(redo.turn), self._owned(),
                                 made)
        friction, restitution, dynamics = spawning.dynamics(group, size, mass, self._values)
        twists = None if group.twists is None else np.asarray(
            group.twists, dtype=float).reshape(-1, TWIST_WIDTH).tolist()
        for k, uid in enumerate(ids):
            if redo.turned[k]:
                self.reset_pose(uid, poses[k][:3], poses[k][3:])
            if twists is not None:
                self.reset_velocity(uid, twists[k][:3], twists[k][3:])
            self._change(uid, -1, **dynamics)
        parameters.set_margin(self, ids[0], group.shape, size)
        return spawning.records(group, ids, size, mass, (friction, restitution), batch, redo)

    def _group_shapes(self, group: BodyGroup, size: tuple[float, ...]) -> tuple[int, int]:
        """A group's collision and visual shapes (shared through the cache)."""
        if group.vertices is not None and group.faces is not None:
            vertices = np.asarray(group.vertices, dtype=float)
            faces = np.asarray(group.faces, dtype=np.int64)
            return (self._shapes.mesh(vertices, faces, group.static),
                    self._shapes.mesh_visual(vertices, faces, group.rgba))
        return (self._shapes.get(group.shape, size),
                self._shapes.visual(group.shape, size, group.rgba))

    @engine_call
    def delete(self, names: Sequence[str]) -> None:
        bodies = self.lookup(names)
        self._maker.remove([b.uid for b in bodies])
        self._removed += len(bodies)
        for name in names:
            del self.bodies[name]
            self.held.pop(name, None)
            self.given.pop(name, None)
            self.frames.pop(name, None)
        self.robots.forget(names)
        # removeBody keeps about 0.9 kB per body (measured with shared shapes) until
        # resetSimulation: an empty world is reset for free, a fuller one rebuilt now and then.
        if not self.bodies:
            self.clear()
        elif rebuild.due(self._removed, self.bodies):
            rebuild.rebuild(self)

    @engine_call
    def clear(self) -> None:
        """resetSimulation: the only call that frees PyBullet's collision shapes."""
        self._bc.resetSimulation()
        self.bodies.clear()
        self.held.clear()
        self.given.clear()
        self._removed = 0
        self.robots, self.frames = Robots(), {}
        self._maker.forget()
        self._shapes.forget()
        parameters.configure_world(self)

    @engine_call
    def reset_dynamics(self) -> None:
        """A new world, every body made again in order at the state just set: Bullet keeps
        contact points and their warm-start impulses across a teleport, so a rewound world
        would otherwise not replay its first run, and would replay it differently after a
        longer run."""
        if self.bodies:
            rebuild.rebuild(self)

    @engine_call
    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        bodies = self.lookup(names)
        if props.mass is not None:
            static = [n for n, b in zip(names, bodies, strict=True) if b.static]
            if static:
                raise InvalidArgumentError(f"entity {static[0]!r} is static: it has no mass")
        for body in bodies:
            if body.model is not None:
                body.model.edits = rebuild.merged(body.model.edits, props)
                self._edit_model(body, props)
            else:
                self._edit_spawned(body, props)

    def _edit_spawned(self, body: _Body, props: BodyProperties) -> None:
        bodyprops.edit_spawned(self._bc, self._change, body, props)

    def _edit_model(self, body: _Body, props: BodyProperties) -> None:
        bodyprops.edit_model(self._bc, self._change, body, props)

    def _owned(self) -> set[int]:
        return {b.uid for b in self.bodies.values()}

    def _uid_of(self, name: str) -> int:
        try:
            return self.bodies[name].uid
        except KeyError:
            raise NotFoundError(f"no entity named {name!r} in the PyBullet world") from None

    def _adopt_model_body(self, uid: int, name: str, batch: int) -> _Body:
        """Register one loaded body (a load's and a rebuild's: articulated.py)."""
        return articulated.adopt_model_body(self, uid, name, batch)

    def lookup(self, names: Sequence[str]) -> list[_Body]:
        try:
            return [self.bodies[n] for n in names]
        except KeyError as exc:
            raise NotFoundError(f"no entity named {exc.args[0]!r} in the PyBullet world") from None

    # -- state (state.py) --------------------------------------------------------
    @engine_call
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Link frames, not PyBullet's centres of mass (frames.py)."""
        return states.get_states(self, names)

    def bounds(self, names: Sequence[str]) -> np.ndarray:
        """PyBullet's own box around each body's (or model link's) collision shapes."""
        rows = np.empty((len(names), 6))
        for row, name in enumerate(names):
            low, high = self._bc.getAABB(*self._link_of(name))
            rows[row] = [*low, *high]
        return rows

    def pose_reader(self, names: Sequence[str]) -> Callable[[], np.ndarray]:
        return engine_call(states.PoseReader(self, names).__call__)

    def shapes(self, names: Sequence[str]) -> list[list[Shape]]:
        return [shapes for shapes, _ in self._link_shapes(names)]

    def shape_meshes(self, names: Sequence[str]) -> list[dict[int, ShapeMesh]]:
        """The convex hulls PyBullet collides model mesh links with (mesh_files.py)."""
        return [meshes for _, meshes in self._link_shapes(names)]

    def _link_shapes(self, names: Sequence[str]
                     ) -> list[tuple[list[Shape], dict[int, ShapeMesh]]]:
        """Each entity's collision shapes and its mesh rows' triangles, found together so
        that the rows of both always agree."""
        found = []
        for name in names:
            uid, link = self._link_of(name)
            found.append(shapes.link_shapes_and_meshes(self._bc, uid, link, self._hulls))
        return found

    def _link_of(self, name: str) -> tuple[int, int]:
        """The PyBullet body and link index of an entity (-1: a body's base)."""
        root, link = self.robots.links.get(name, (name, -1))
        [body] = self.lookup([root])
        return body.uid, link

    def _read(self, ids: list[int]) -> tuple[np.ndarray, np.ndarray]:
        return states.read(self, ids)

    @engine_call
    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        states.set_states(self, names, poses, twists)

    @engine_call
    def step(self, count: int) -> None:
        """stepSimulation alone, unless targets or wrenches are held: then they are
        applied before each step (they last one step in PyBullet)."""
        step = self._step
        self.held.clear()
        self.given.clear()
        if self.robots.busy():
            actuate, bc, uid_of, dt = self.robots.actuate, self._bc, self._uid_of, \
                self.timestep
            for _ in range(count):
                actuate(bc, uid_of, dt)
                step()
            return
        for _ in range(count):
            step()


    @engine_call
    def state_within(self, max_position: float, max_speed: float) -> bool:
        return states.state_within(self, max_position, max_speed)

    @engine_call
    def properties(self, names: Sequence[str]) -> np.ndarray:
        """Spawned bodies from what the engine last gave PyBullet (getDynamicsInfo reports
        a rigid body's restitution as 0); models from PyBullet, the mass summed over links."""
        links = self.robots.links
        self.lookup([name for name in names if name not in links])  # NotFound for others
        rows = [articulated.link_properties(self, name) if name in links
                else self._properties(self.bodies[name]) for name in names]
        return np.array(rows, dtype=float).reshape(len(rows), 3)

    def _properties(self, body: _Body) -> tuple[float, float, float]:
        return bodyprops.properties(self._bc, body)

    # -- models ---------------------------------------------------------------------------
    @engine_call
    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str, *, fixed_base: bool = True) -> list[EntityInfo]:
        """URDF (one model) or MJCF (one model per top-level body, plus one for the world's
        own geoms), roots and links (articulated.py). Text is loaded from a
        temporary file, so relative mesh paths only work when a path is given."""
        return articulated.load(self, fmt, text, path, prefix, fixed_base)

    # -- joints, targets and wrenches (articulated.py) -------------------------------------
    def joints(self) -> list[JointInfo]:
        return articulated.joints(self)

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return articulated.get_joint_states(self, names)

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        articulated.set_joint_states(self, names, positions, velocities)

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        articulated.set_joint_targets(self, names, mode, targets, kp, kd, max_effort)

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        set_damping(self._bc, self.robots.models, self._uid_of, names, damping)

    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        articulated.set_wrenches(self, names, wrenches, points)

    def clear_wrenches(self, names: Sequence[str] | None) -> None:
        articulated.clear_wrenches(self, names)

    def restore_joints(self) -> None:
        articulated.restore_joints(self)

    # -- perception (perception.py) ---------------------------------------------------------
    def render(self, cameras: Sequence[CameraView]
               ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
        """TinyRenderer, one getCameraImage per camera (render.py)."""
        return perception.render(self, cameras)

    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
                ) -> RayHits:
        """rayTestBatch, hits on spawned primitives made exact (rays.py)."""
        return perception.raycast(self, origins, directions, max_length)

    def contacts(self, names: Sequence[str] | None) -> ContactPoints:
        """getContactPoints of the last step, normals from the first entity to the second."""
        return perception.contacts(self, names)

    # -- snapshots (snapshot/) ------------------------------------------------
    @engine_call
    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        """The world as plain data: every body's records, model texts, articulations, targets,
        wrenches, parameters and states. Bullet's contact points and warm starts cannot be
        read out, so a restore starts without them, as ``reset_dynamics`` leaves a world.
        The promise (on the same PyBullet build): a fresh engine restored from the
        snapshot, given the same steps and requests, has the same states bit for bit as
        this world, which ``canonical`` rebuilds now for that (its own continuation then
        differs from the one it would have had, as after ``reset_dynamics``); with
        ``canonical`` False this world is left untouched, and the restore goes on bit for
        bit as this world would after ``reset_dynamics`` now."""
        return snapshots.snapshot(self, canonical)

    @engine_call
    def restore(self, data: dict[str, Any]) -> None:
        """Make this fresh engine the world ``data`` describes (checked whole first:
        InvalidArgumentError naming the field for anything malformed)."""
        snapshots.restore(self, data)

    def entity_names(self) -> list[str]:
        return [*self.bodies, *self.robots.links]

    @engine_call
    def clone(self) -> PybulletEngine:
        """As ``restore(snapshot(canonical=False))`` into a fresh engine, without the plain
        data between them (snapshot.py); this world is untouched."""
        return snapshots.clone_into(self, type(self)())

    # -- life -----------------------------------------------------------------------------
    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._bc.disconnect()

