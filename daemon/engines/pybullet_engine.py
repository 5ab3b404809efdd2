"""The PyBullet engine: a headless Bullet world, one per BulletClient (several can live in
one process, as during an engine switch).

Spawned bodies are plain rigid bodies (``useMaximalCoordinates``): Bullet's continuous
collision detection works only for those, they carry no default damping (a one-link
multibody has 0.04, which slows a free fall by 7 % in one second), and they step and read
faster. Loaded models are multibodies (their joints need it), with damping set to zero.

Contacts: PyBullet multiplies the two bodies' values at a contact, for friction and for
restitution alike, so a body with restitution 0.9 bounces off a body with restitution 0
hardly at all. Restitution is also zero below ``pybullet.restitution_velocity_threshold``.
The defaults (restitution 0.8275, friction 0.5 on every body: e = 0.685, mu = 0.25 for
any pair; early contacts from 0.01 m instead of Bullet's 0.02, so that slow balls keep
their bounce) are calibrated on the Galton board in both release modes; the solver
settings (10 iterations, pyramid friction) are the cheapest that keep it.
docs/physics/pybullet.md has the measurements. ``contactBreakingThreshold`` is a global of
the PyBullet module: every engine sets its own value when it starts, and the last
``set_params`` wins for all engines of the process.

Memory: removeBody keeps about 0.9 kB per body even with shared collision shapes; only
resetSimulation frees it, which ``clear`` does, and ``delete`` does when the world empties
or, past a count of removed bodies, by rebuilding the world (pybullet_rebuild.py). Visual
meshes are made once per process (pybullet_shapes.shared_mesh): createVisualShape never
lets go of the lists it is given.

Rewinding: ``reset_dynamics`` rebuilds the world too, every body made again as it was first
made, so that a stopped world replays its first run bit for bit (Bullet would otherwise keep
contact points and their warm starts across the teleport).

The engine is three parts: this module (bodies, states, models), ``Parameters``
(pybullet_params.py) and ``Rebuilding`` (pybullet_rebuild.py). Plain functions do the rest:
a spawn group's values and books (pybullet_spawn.py), a body's updates and properties
(pybullet_props.py), a model load's checks and names (pybullet_models.py).
"""

from __future__ import annotations

import functools
import importlib.metadata
import itertools
import typing
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engine import (
    FEATURE_DELETE,
    FEATURE_LOAD_MODEL,
    FEATURE_SET_STATE,
    FEATURE_SPAWN,
    FEATURE_STATIC_POSE,
    FEATURE_UPDATE_FRICTION,
    FEATURE_UPDATE_MASS,
    FEATURE_UPDATE_RESTITUTION,
    FEATURE_UPDATE_RGBA,
    Engine,
)
from galton.daemon.engines import pybullet_models as models
from galton.daemon.engines import pybullet_props as bodyprops
from galton.daemon.engines import pybullet_rebuild as rebuild
from galton.daemon.engines import pybullet_spawn as spawning
from galton.daemon.engines.pybullet_models import MODEL_FORMATS
from galton.daemon.engines.pybullet_params import SPECS, Parameters
from galton.daemon.engines.pybullet_rebuild import Body as _Body
from galton.daemon.engines.pybullet_rebuild import Rebuilding
from galton.daemon.engines.pybullet_shapes import (
    BodyMaker,
    ShapeCache,
    link_masses,
    load_bodies,
)
from galton.daemon.params import check_updates
from galton.protocol import (
    PROTOCOL_VERSION,
    BodyGroup,
    BodyProperties,
    Capabilities,
    EntityInfo,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
    OperationFailedError,
)
from galton.protocol.model import BODY_SHAPES, POSE_WIDTH, TWIST_WIDTH

_P = typing.ParamSpec("_P")
_R = TypeVar("_R")


def _engine_call(method: Callable[_P, _R]) -> Callable[_P, _R]:
    """Report PyBullet's own failures (a lost connection, a refused call) as
    OperationFailedError, as the Engine contract asks."""
    @functools.wraps(method)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        try:
            return method(*args, **kwargs)
        except pybullet.error as exc:
            raise OperationFailedError(f"PyBullet {method.__name__} failed: {exc}") from exc
    return wrapper


class PybulletEngine(Parameters, Rebuilding, Engine):
    """Named rigid bodies in a headless PyBullet world."""

    name = "pybullet"

    def __init__(self) -> None:
        self._bc = BulletClient(connection_mode=pybullet.DIRECT)
        self._closed = False
        bc = self._bc
        # Bound once: BulletClient builds a new functools.partial on every attribute access.
        self._get_pose = bc.getBasePositionAndOrientation
        self._get_velocity = bc.getBaseVelocity
        self._reset_pose = bc.resetBasePositionAndOrientation
        self._reset_velocity = bc.resetBaseVelocity
        self._change = bc.changeDynamics
        self._step = bc.stepSimulation
        self._shapes = ShapeCache(bc)
        self._bodies: dict[str, _Body] = {}
        self._maker = BodyMaker(bc)
        self._values: dict[str, Any] = {name: spec.default for name, spec in SPECS.items()}
        self._removed = 0  # bodies removed since resetSimulation last ran
        self._held: dict[str, rebuild.Held] = {}  # states a rebuild could not set bit for bit
        # Poses given to PyBullet (spawn, set_states) since the last step: a rebuild sets
        # them again as given, which reading them back (a rotation matrix) cannot promise.
        self._given: dict[str, list[float]] = {}
        self._batches = itertools.count()  # spawn groups and model loads, in order
        self.rebuilds = 0
        self._configure_world()

    # -- description ----------------------------------------------------------------------
    def capabilities(self) -> Capabilities:
        return Capabilities(
            engine=self.name,
            engine_version=importlib.metadata.version("pybullet"),
            protocol_version=PROTOCOL_VERSION,
            body_shapes=BODY_SHAPES,
            model_formats=MODEL_FORMATS,
            features=(FEATURE_SPAWN, FEATURE_DELETE, FEATURE_SET_STATE, FEATURE_UPDATE_MASS,
                      FEATURE_UPDATE_FRICTION, FEATURE_UPDATE_RESTITUTION, FEATURE_UPDATE_RGBA,
                      FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE),
            params={name: spec.describe() for name, spec in SPECS.items()},
        )

    @property
    def timestep(self) -> float:
        return float(self._values["timestep"])

    # -- parameters -----------------------------------------------------------------------
    def get_params(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._values.items()}

    @_engine_call
    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, SPECS, params)
        self._values.update(clean)
        self._apply(clean)

    # -- bodies ---------------------------------------------------------------------------
    @_engine_call
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        taken = [n for g in groups for n in g.names if n in self._bodies]
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
        self._bodies.update(bodies)
        for group in groups:
            self._given.update(zip(group.names, np.asarray(
                group.poses, dtype=float).reshape(-1, POSE_WIDTH).tolist(), strict=True))

    def _spawn_group(self, group: BodyGroup, made: list[int], batch: int,
                     redo: rebuild.Redo | None = None) -> dict[str, _Body]:
        """The group's bodies in (at most) one createMultiBody call, all turned like the
        first, then each one's own orientation where it differs, velocity and dynamics. A
        rebuild (``redo``) makes them as they were first made."""
        spawning.check_group(group)
        size = tuple(float(s) for s in group.size)
        poses = np.asarray(group.poses, dtype=float).reshape(-1, POSE_WIDTH).tolist()
        if redo is None:
            redo = spawning.first_redo(poses)
        mass = spawning.group_mass(group, size)
        ids = self._maker.create(mass, self._shapes.get(group.shape, size),
                                 self._shapes.visual(group.shape, size, group.rgba),
                                 [pose[:3] for pose in poses], list(redo.turn), self._owned(),
                                 made)
        friction, restitution, dynamics = spawning.dynamics(group, size, mass, self._values)
        twists = None if group.twists is None else np.asarray(
            group.twists, dtype=float).reshape(-1, TWIST_WIDTH).tolist()
        for k, uid in enumerate(ids):
            if redo.turned[k]:
                self._reset_pose(uid, poses[k][:3], poses[k][3:])
            if twists is not None:
                self._reset_velocity(uid, twists[k][:3], twists[k][3:])
            self._change(uid, -1, **dynamics)
        self._set_margin(ids[0], group.shape, size)
        return spawning.books(group, ids, size, mass, (friction, restitution), batch, redo)

    @_engine_call
    def delete(self, names: Sequence[str]) -> None:
        bodies = self._lookup(names)
        self._maker.remove([b.uid for b in bodies])
        self._removed += len(bodies)
        for name in names:
            del self._bodies[name]
            self._held.pop(name, None)
            self._given.pop(name, None)
        # removeBody keeps about 0.9 kB per body (measured with shared shapes) until
        # resetSimulation: an empty world is reset for free, a fuller one rebuilt now and then.
        if not self._bodies:
            self.clear()
        elif rebuild.due(self._removed, self._bodies):
            self._rebuild()

    @_engine_call
    def clear(self) -> None:
        """resetSimulation: the only call that frees PyBullet's collision shapes."""
        self._bc.resetSimulation()
        self._bodies.clear()
        self._held.clear()
        self._given.clear()
        self._removed = 0
        self._maker.forget()
        self._shapes.forget()
        self._configure_world()

    @_engine_call
    def reset_dynamics(self) -> None:
        """A new world, every body made again in order at the state just set: Bullet keeps
        contact points and their warm-start impulses across a teleport, so a rewound world
        would otherwise not replay its first run, and would replay it differently after a
        longer run."""
        if self._bodies:
            self._rebuild()

    @_engine_call
    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        bodies = self._lookup(names)
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
        return {b.uid for b in self._bodies.values()}

    def _lookup(self, names: Sequence[str]) -> list[_Body]:
        try:
            return [self._bodies[n] for n in names]
        except KeyError as exc:
            raise NotFoundError(f"no entity named {exc.args[0]!r} in the PyBullet world") from None

    # -- state ----------------------------------------------------------------------------
    @_engine_call
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        poses, twists = self._read([b.uid for b in self._lookup(names)])
        if self._held:  # right after a rebuild: the states as they were before it
            rebuild.report_held(self._held, names, poses, twists)
        return poses, twists

    def _read(self, ids: list[int]) -> tuple[np.ndarray, np.ndarray]:
        """One call per body and per quantity (PyBullet has no batch getter): the nested
        tuples are flattened straight into numpy, the cheapest way measured."""
        n, flat = len(ids), itertools.chain.from_iterable
        poses = np.fromiter(flat(flat(map(self._get_pose, ids))), float, n * POSE_WIDTH)
        twists = np.fromiter(flat(flat(map(self._get_velocity, ids))), float, n * TWIST_WIDTH)
        return poses.reshape(n, POSE_WIDTH), twists.reshape(n, TWIST_WIDTH)

    @_engine_call
    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        """A pose alone keeps each body's twist, a twist alone its pose, as on every engine:
        resetBasePositionAndOrientation zeroes the twist, so it is read first and set again."""
        ids = [b.uid for b in self._lookup(names)]
        if self._held:
            rebuild.release_held(self._held, names, poses is not None, twists is not None)
        if poses is not None:
            rows = np.asarray(poses, dtype=float).tolist()
            if twists is None:
                twists = self._read(ids)[1]
            for uid, pose in zip(ids, rows, strict=True):
                self._reset_pose(uid, pose[:3], pose[3:])
            self._given.update(zip(names, rows, strict=True))
        if twists is not None:
            for uid, twist in zip(ids, np.asarray(twists, dtype=float).tolist(), strict=True):
                self._reset_velocity(uid, twist[:3], twist[3:])

    @_engine_call
    def step(self, count: int) -> None:
        step = self._step
        self._held.clear()
        self._given.clear()
        for _ in range(count):
            step()

    @_engine_call
    def state_within(self, max_position: float, max_speed: float) -> bool:
        """Static bodies cannot move in a step, so only the others are read: a board's
        hundreds of pins cost nothing here. Bullet itself reports no divergence: a ball at
        x = 4e299 is finite, and falls on there as if nothing were wrong."""
        moving = [b.uid for b in self._bodies.values() if not b.static]
        if not moving:
            return True
        poses, twists = self._read(moving)
        return bool(np.isfinite(poses).all() and np.isfinite(twists).all()
                    and np.abs(poses[:, :3]).max() <= max_position
                    and np.abs(twists).max() <= max_speed)

    @_engine_call
    def properties(self, names: Sequence[str]) -> np.ndarray:
        """Spawned bodies from what the engine last gave PyBullet (getDynamicsInfo reports
        a rigid body's restitution as 0); models from PyBullet, the mass summed over links."""
        rows = [self._properties(body) for body in self._lookup(names)]
        return np.array(rows, dtype=float).reshape(len(rows), 3)

    def _properties(self, body: _Body) -> tuple[float, float, float]:
        return bodyprops.properties(self._bc, body)

    # -- models ---------------------------------------------------------------------------
    @_engine_call
    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str) -> list[EntityInfo]:
        """URDF (one body) or MJCF (one body per top-level body, plus one for the world's
        own geoms). Text is loaded from a temporary file, so relative mesh paths only work
        when a path is given. A model's pose is its base's centre of mass (PyBullet's)."""
        source = models.model_text(fmt, text, path)
        ids = load_bodies(self._bc, self._maker, fmt, source, path)
        try:
            return self._adopt_model(fmt, ids, prefix, source, path)
        except BaseException:
            self._maker.remove(ids)
            for name in [n for n, b in self._bodies.items() if b.uid in ids]:
                del self._bodies[name]
            raise

    def _adopt_model(self, fmt: str, ids: list[int], prefix: str, text: str,
                     path: str | None) -> list[EntityInfo]:
        """Name the loaded bodies, refuse names in use, and register the bodies with what it
        takes to load them again."""
        names = models.body_names(self._bc, fmt, ids, prefix, self._bodies)
        batch, infos = next(self._batches), []
        for index, (uid, name) in enumerate(zip(ids, names, strict=True)):
            body = self._adopt_model_body(uid, name, batch)
            poses, twists = self._read([uid])
            body.model = model = rebuild.Model(fmt, text, path, index,
                                               link_masses(self._bc, uid, body.links),
                                               (poses[0].tolist(), twists[0].tolist()))
            infos.append(models.entity_info(self._bc, name, body, model))
        return infos

    def _adopt_model_body(self, uid: int, name: str, batch: int) -> _Body:
        """Register one loaded body (see pybullet_models.model_body)."""
        body = models.model_body(self._bc, self._change,
                                 self._values["pybullet.ccd_swept_sphere_radius"], uid, batch)
        self._bodies[name] = body
        return body

    # -- life -----------------------------------------------------------------------------
    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._bc.disconnect()

