"""The ODE engine, set up as Webots sets it up: ``dWorldStep``, world CFM 1e-5 and ERP 0.2,
contacts with Coulomb friction 1, bounce 0.5 above 0.01 m/s, soft CFM 0.001 and soft ERP
0.2, at most 10 contact joints per pair, bodies asleep after 1 s idle (params.py; the
Webots sources in docs/ENGINES.md).

One world, one sweep-and-prune space holding every geom, one group of contact joints
emptied before each step's collision. The class is the Engine contract, each method short
or a call to the module of its part: bodies (spawn.py; meshes: trimesh.py), states
(state.py), collision and contact reports (contacts.py), ray casts (rays.py), snapshots
(snapshot/, fast_state.py), robots (joints.py, models.py).

Determinism: ``dWorldStep`` draws no random numbers, ODE's space visits geoms in the order
they were made, and a restore makes them again in that order, so the same steps give the
same states bit for bit (QuickStep's random constraint order is seeded before each step).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from galton.daemon.engines.base import (
    ContactPoints,
    Engine,
    RayHits,
    Shape,
)
from galton.daemon.engines.ode import fast_state
from galton.daemon.engines.ode import snapshot as snapshots
from galton.daemon.engines.ode import spawn as spawning
from galton.daemon.engines.ode import state as states
from galton.daemon.engines.ode.contacts import Collider, sync_sleep
from galton.daemon.engines.ode.joints import Robots, place
from galton.daemon.engines.ode.models import MODEL_FORMATS, load_urdf
from galton.daemon.engines.ode.native import LIB, SAP_AXES_XZY, version
from galton.daemon.engines.ode.params import PARAMS, SURFACE_DEFAULTS, default_keys
from galton.daemon.engines.ode.rays import RayCaster
from galton.daemon.engines.ode.shapes import model_shapes
from galton.daemon.engines.ode.spawn import Body
from galton.daemon.engines.params import check_updates
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    EntityInfo,
    FeatureUnsupportedError,
    InvalidArgumentError,
    JointInfo,
    NameNotUniqueError,
    NotFoundError,
)

MAX_SPIN = 1e8  # rad/s: the most spin ODE integrates in a body (above the protocol's MAX_TWIST)


class OdeEngine(Engine):
    """Named rigid bodies in an ODE world stepped as Webots steps it."""

    name = "ode"
    param_specs = PARAMS
    model_formats = MODEL_FORMATS
    spawn_inertia = True

    def __init__(self) -> None:
        self._world = int(LIB.dWorldCreate())
        # ODE aborts the process (dxNormalize4) on a quaternion its step made infinite; with
        # every pushed number bounded (docs/protocol.md, "Bounds"), capping the spin each body
        # integrates keeps it finite. The cap is far past max_speed: a body near it has
        # diverged, and the step's check says so.
        LIB.dWorldSetMaxAngularSpeed(self._world, MAX_SPIN)
        # Sweep and prune: a hash space rebuilds its table every step, 0.26 ms for the
        # paper board's 121 geoms alone; this halves the cost of a 100-ball step.
        self._space = int(LIB.dSweepAndPruneSpaceCreate(None, SAP_AXES_XZY))
        self._bodies: dict[str, Body] = {}
        self._by_geom: dict[int, Body] = {}
        self._moving: list[Body] = []
        self._serials = itertools.count()
        self._wrenches: dict[str, list[float]] = {}
        self._values: dict[str, Any] = {n: s.default for n, s in PARAMS.items()}
        self._collider = Collider(self._world, self._space, self._by_geom)
        self._rays = RayCaster(self._space, self._by_geom)
        self._robots = Robots()
        self._diverged = False
        self._closed = False
        self.generation = 0  # counts changes of the bodies: a pose reader's addresses hold
        # Webots turns damping off (WbOdeContext: damping thresholds 0) and sets none.
        LIB.dWorldSetLinearDampingThreshold(self._world, 0.0)
        LIB.dWorldSetAngularDampingThreshold(self._world, 0.0)
        self._apply(self._values)

    # -- description and parameters ---------------------------------------------------------
    @classmethod
    def engine_version(cls) -> str:
        return version()

    @property
    def timestep(self) -> float:
        return float(self._values["timestep"])

    def get_params(self) -> dict[str, Any]:
        return {k: list(v) if isinstance(v, tuple) else v for k, v in self._values.items()}

    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, PARAMS, params)
        self._values.update(clean)
        self._apply(clean)

    def _apply(self, values: dict[str, Any]) -> None:
        world, v = self._world, self._values
        if "gravity" in values:
            LIB.dWorldSetGravity(world, *v["gravity"])
        LIB.dWorldSetCFM(world, v["ode.cfm"])
        LIB.dWorldSetERP(world, v["ode.erp"])
        LIB.dWorldSetQuickStepNumIterations(world, v["solver_iterations"])
        LIB.dWorldSetAutoDisableFlag(world, int(v["ode.auto_disable"]))
        LIB.dWorldSetAutoDisableTime(world, v["ode.disable_time"])
        LIB.dWorldSetAutoDisableSteps(world, 0)  # as Webots: time alone decides
        LIB.dWorldSetAutoDisableLinearThreshold(world, v["ode.disable_linear_threshold"])
        LIB.dWorldSetAutoDisableAngularThreshold(world, v["ode.disable_angular_threshold"])
        if any(k.startswith("ode.disable") or k == "ode.auto_disable" for k in values):
            for body in self._moving:
                LIB.dBodySetAutoDisableDefaults(body.body)
                if body.name in self._wrenches:
                    LIB.dBodySetAutoDisableFlag(body.body, 0)
        self._collider.configure(v)
        if values.keys() & SURFACE_DEFAULTS:
            for body in self._bodies.values():
                friction_key, restitution_key = default_keys(body.static)
                if body.follows_friction:
                    body.friction = v[friction_key]
                if body.follows_restitution:
                    body.restitution = v[restitution_key]

    # -- bodies ------------------------------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        names = [n for g in groups for n in g.names]
        taken = [n for n in names if n in self._bodies or n in self._robots.links]
        if taken or len(set(names)) != len(names):
            raise NameNotUniqueError(f"an entity named {(taken or names)[0]!r} already exists")
        made: list[Body] = []
        try:
            for group in groups:
                made.extend(spawning.spawn_group(self._world, self._space, group, self._values))
        except BaseException:
            spawning.destroy(made)
            raise
        self._adopt(made)

    def _adopt(self, made: list[Body]) -> None:
        self.generation += 1
        for body in made:
            body.serial = next(self._serials)
            self._bodies[body.name] = body
            for geom in body.geoms():
                self._by_geom[geom] = body
            if not body.static:
                self._moving.append(body)

    def delete(self, names: Sequence[str]) -> None:
        bodies = self._lookup(names)
        self.generation += 1
        roots = [b for b in bodies if b.model == b.name]
        if any(b.model is not None and b.model != b.name for b in bodies):
            raise InvalidArgumentError("a model's link goes with its model: delete the root")
        for root in roots:
            bodies.extend(b for b in self._robots.links_of(root.name, self._bodies)
                          if b not in bodies)
            self._robots.forget(root.name)
        self._collider.let_go({body.name for body in bodies})
        for body in bodies:
            del self._bodies[body.name]
            for geom in body.geoms():
                del self._by_geom[geom]
            self._wrenches.pop(body.name, None)
        self._moving = [b for b in self._moving if b.name in self._bodies]
        spawning.destroy(bodies)

    def clear(self) -> None:
        self.generation += 1
        self._collider.forget()
        self._robots.destroy()
        self._robots = Robots()
        spawning.destroy(list(self._bodies.values()))
        self._bodies.clear()
        self._by_geom.clear()
        self._moving.clear()
        self._wrenches.clear()
        self._diverged = False

    def _lookup(self, names: Sequence[str]) -> list[Body]:
        try:
            return [self._bodies[n] for n in names]
        except KeyError as exc:
            raise NotFoundError(f"no entity named {exc.args[0]!r} in the ODE world") from None

    def shapes(self, names: Sequence[str]) -> list[list[Shape]]:
        """A link's collision shapes as loaded (shapes.py: a mesh is already its box)."""
        return model_shapes(self._lookup(names))

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        bodies = self._lookup(names)
        if props.mass is not None and any(b.static for b in bodies):
            static = next(b.name for b in bodies if b.static)
            raise InvalidArgumentError(f"entity {static!r} is static: it has no mass")
        if props.mass is not None and any(b.model is not None for b in bodies):
            raise FeatureUnsupportedError("the ode engine does not change a model's mass")
        for body in bodies:
            if props.mass is not None:
                spawning.set_mass(body, props.mass)
            if props.friction is not None:
                body.friction, body.follows_friction = props.friction, False
            if props.restitution is not None:
                body.restitution, body.follows_restitution = props.restitution, False
            if props.rgba is not None:
                body.rgba = props.rgba

    def properties(self, names: Sequence[str]) -> np.ndarray:
        rows = [(self._robots.model_mass(b.name, self._bodies) if b.model == b.name
                 else b.mass, b.friction, b.restitution) for b in self._lookup(names)]
        return np.array(rows, dtype=float).reshape(len(rows), 3)

    # -- states and stepping ------------------------------------------------------------------
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        return states.read(self._lookup(names))

    def pose_reader(self, names: Sequence[str]) -> Callable[[], np.ndarray]:
        """Poses gathered from ODE's memory in one index; looked up again after the bodies
        change, as a freed body's memory must never be read."""
        fixed = list(names)
        reader = states.PoseReader(self._lookup(fixed))
        made_at = self.generation

        def read() -> np.ndarray:
            nonlocal reader, made_at
            if made_at != self.generation:
                reader, made_at = states.PoseReader(self._lookup(fixed)), self.generation
            return reader()
        return read

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        bodies = self._lookup(names)
        if states.wild(poses) or states.wild(twists):
            self._diverged = True  # not handed to ODE: such a world has diverged
            return
        states.write(bodies, poses, twists)
        for body in bodies:
            if body.model == body.name:  # a model's root carries its links
                place(self._robots.models[body.name], self._bodies, {})

    def step(self, count: int) -> None:
        collide, world, dt = self._collider.collide, self._world, self.timestep
        quick = self._values["ode.stepper"] == "quick"
        stepper = LIB.dWorldQuickStep if quick else LIB.dWorldStep
        sleepy = self._values["ode.auto_disable"]
        moving, busy = self._moving, self._robots.busy()
        for k in range(count):
            if self._diverged:
                return  # ODE's solver may never return from a NaN: stop stepping it
            collide(k == count - 1)
            if self._wrenches:
                self._push()
            if busy:
                self._robots.actuate()
            if quick:
                LIB.dRandSetSeed(0)
            stepper(world, dt)
            if busy:
                self._robots.settle()
            if sleepy:
                sync_sleep(moving)
            if moving and not states.tame(moving):
                self._diverged = True

    def _push(self) -> None:
        for name, wrench in self._wrenches.items():
            handle = self._bodies[name].body
            LIB.dBodyAddForce(handle, *wrench[:3])
            LIB.dBodyAddTorque(handle, *wrench[3:])

    def state_within(self, max_position: float, max_speed: float) -> bool:
        if self._diverged:
            return False
        return states.within(self._moving, max_position, max_speed)

    def reset_dynamics(self) -> None:
        """Restart every body's idle counters (a sleeping body stays asleep): all the hidden
        state ODE keeps between steps."""
        self._collider.forget()
        for body in self._moving:
            asleep = not body.awake
            LIB.dBodyEnable(body.body)
            if asleep:
                LIB.dBodyDisable(body.body)
        self._diverged = False

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        self._robots.set_damping(names, damping, self._bodies)

    # -- wrenches ---------------------------------------------------------------------------
    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        bodies = self._lookup(names)
        static = [b.name for b in bodies if b.static or b.welded]
        if static:
            raise InvalidArgumentError(f"entity {static[0]!r} is static or a fixed base: no "
                                       "wrench moves it")
        for k, body in enumerate(bodies):
            force, torque = wrenches[k, :3], wrenches[k, 3:]
            if points is not None:
                torque = torque + np.cross(points[k] - body.state[:3], force)
            self._wrenches[body.name] = [*force.tolist(), *torque.tolist()]
            states.wake(body)
            LIB.dBodySetAutoDisableFlag(body.body, 0)  # a held push keeps it awake

    def clear_wrenches(self, names: Sequence[str] | None) -> None:
        for name in list(self._wrenches) if names is None else names:
            if self._wrenches.pop(name, None) is not None and name in self._bodies:
                LIB.dBodySetAutoDisableDefaults(self._bodies[name].body)

    # -- perception ---------------------------------------------------------------------------
    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
                ) -> RayHits:
        return RayHits(*self._rays.cast(origins, directions, max_length))

    def contacts(self, names: Sequence[str] | None
                 ) -> ContactPoints:
        wanted = None if names is None else set(names)
        if wanted is not None:
            self._lookup(list(wanted))
        return ContactPoints(*self._collider.report(wanted))

    # -- models and joints (joints.py, models.py) ----------------------------------------------
    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str, *, fixed_base: bool = True) -> list[EntityInfo]:
        if fmt not in MODEL_FORMATS:
            raise FeatureUnsupportedError(
                f"the ode engine loads {', '.join(MODEL_FORMATS)} models, not {fmt!r}")
        made, infos = load_urdf(self._world, self._space, self._robots, text, path, prefix,
                                fixed_base, self._values, set(self._bodies))
        self._adopt(made)
        return infos

    def joints(self) -> list[JointInfo]:
        return self._robots.infos()

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._robots.states(names)

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        self._robots.teleport(names, positions, velocities, self._bodies)

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        self._robots.hold(names, mode, targets, kp, kd, max_effort, self._bodies)

    # -- snapshots (snapshot/, fast_state.py) -----------------------------------------------
    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        """Every body's and link's own doubles, wake flags, wrenches, joint targets and the
        parameters (snapshot/format.py); ``canonical`` first restarts the idle counters."""
        return snapshots.snapshot(self, canonical=canonical)

    def restore(self, data: dict[str, Any]) -> None:
        snapshots.restore(self, data)

    def save_state(self) -> object | None:
        """The bodies' own doubles, wake flags, wrenches and joint targets (fast_state)."""
        return fast_state.save(self)

    def load_state(self, state: object) -> bool:
        return fast_state.load(self, state)

    def restore_joints(self) -> None:
        self._robots.rewind(self._bodies)
        self.clear_wrenches(None)

    # -- life -----------------------------------------------------------------------------------
    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.clear()
            self._rays.close()
            self._collider.close()
            LIB.dSpaceDestroy(self._space)
            LIB.dWorldDestroy(self._world)

