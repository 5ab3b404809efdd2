"""The MuJoCo engine: a world built with ``mujoco.MjSpec`` and edited while it runs.

A model load, and a delete that removes bodies, edit the spec and recompile it once, in
place (``MjSpec.recompile``), so the bodies already there keep their positions, velocities
and warm starts. A spawn does too unless the pool holds enough parked, pre-compiled bodies of
the group's kind: then it binds the names to them, no compile (``parked``); a compiling
spawn adds spare parked twins, and delete and clear park spawned bodies again (no compile
when they all fit in the pool).

Dynamic bodies have a free joint; static ones are jointless children of the
world whose pose is written into the compiled model (and the spec), so moving them needs no
recompile, and balls resting on them can sleep (see ``parked``). States are
read and written in batches through numpy index arrays (``state``) rebuilt after each
compile: nothing in Python runs per body per step.

Every change is all or nothing. What can fail (a recompile MuJoCo rejects, a world MuJoCo
cannot hold) comes before anything that cannot; a failed recompile leaves the model and data
in use untouched, and the spec's edits and the engine's records are put back. Removed bodies
cannot be put back, so a delete in a world holding a loaded model (whose references may
reach other bodies) is first tried on a copy of the spec.

The engine keeps the compiled world, its index and the time; its verbs that edit the
spec are plain functions of the engine in their own modules: ``spawn``,
``models`` (MJCF and URDF loads: a model's root and links are entities),
``removal`` (delete, clear), ``teleport`` (set_states) and ``props``
(update, properties, MuJoCo's contact rules); ``entities`` holds what they share.
Loaded models' joints, with one actuator each holding a target, are kept by
``joints``, wrenches by ``wrench``; both records are written again into the
compiled model after every compile. The compile in place and the rows it indexes are in
``compiled``; stepping, its periodic looks and the rewind in ``stepping``.
Cameras, rays and contacts (``render``, ``rays``, ``contacts``; what the last step left,
kept until the next: ``observed``) see entities only, never parked bodies. The engine's
parameters are ``params``; what it writes into the ``MjSpec`` is ``mj_spec``; a loaded
model's colliding shapes ``shapes``; the guard against sleeping balanced on a pin
``sleep_guard``; snapshots ``snapshot`` and states kept in memory ``fast_state``.

Size: MuJoCo holds at most ``params.MAX_BODIES`` bodies, and its compile costs
O(free bodies x degrees of freedom): about 1.6 s for 4,000 free spheres, four times that for
twice as many. Everything else here is linear in the bodies a call touches.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, ClassVar

import mujoco
import numpy as np

from galton.daemon.engines.base import (
    CameraView,
    ContactPoints,
    Engine,
    RayHits,
    Shape,
    ShapeMesh,
)
from galton.daemon.engines.geometry import check_group
from galton.daemon.engines.mujoco import clone as cloning
from galton.daemon.engines.mujoco import compiled as compiling
from galton.daemon.engines.mujoco import fast_state, models, removal, teleport, wrench
from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import observed as observing
from galton.daemon.engines.mujoco import params as mparams
from galton.daemon.engines.mujoco import parked as mp
from galton.daemon.engines.mujoco import props as mpr
from galton.daemon.engines.mujoco import rays as sensing
from galton.daemon.engines.mujoco import render as rendering
from galton.daemon.engines.mujoco import shapes as colliders
from galton.daemon.engines.mujoco import snapshot as snapshots
from galton.daemon.engines.mujoco import spawn as adding
from galton.daemon.engines.mujoco import state as mst
from galton.daemon.engines.mujoco import stepping as timing
from galton.daemon.engines.mujoco.entities import Entity
from galton.daemon.engines.mujoco.joints import Joints
from galton.daemon.engines.mujoco.poses import PoseReader
from galton.daemon.engines.mujoco.sleep_guard import SleepGuard
from galton.daemon.engines.mujoco.wrench import Wrenches
from galton.daemon.engines.params import check_updates
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    EntityInfo,
    JointInfo,
    NotFoundError,
)

# Contacts at which MuJoCo's worker threads start helping, and below which they stop.
WORKERS_ON_CONTACTS = 400
WORKERS_OFF_CONTACTS = 200


class MujocoEngine(Engine):
    """A MuJoCo world of named bodies; see the module docstring for how it is kept."""

    name: ClassVar[str] = "mujoco"
    releases_gil_while_stepping: ClassVar[bool] = True  # mj_step runs without the GIL
    param_specs = mparams.PARAMS
    model_formats = models.FORMATS
    spawn_inertia = True
    # What the last step left, frozen before an edit until the next step (a class default:
    # a clone is made without __init__).
    observed: observing.Observed | None = None
    closed = False  # its MjData was given back (fast_state.give_back): never twice
    # The spec and model it shares with its forks or source, read-only until ``own`` (clone).
    sharing: cloning.Sharing | None = None

    def __init__(self) -> None:
        ms.route_warnings()
        self.values: dict[str, Any] = {n: p.default for n, p in mparams.PARAMS.items()}
        self.entities: dict[str, Entity] = {}
        self.diverged = False
        self.crowded = False
        self.workers = 0
        self.steps_since_look = 0
        self.cameras: rendering.CameraRig | None = None  # made by the first render
        self.build_empty()

    # -- compile & index ----------------------------------------------------------------
    def build_empty(self) -> None:
        self.parked = mp.ParkedBodies()
        self.mj_spec = mujoco.MjSpec()
        self.mj_spec.modelname = "galton"
        self.mj_spec.copy_during_attach = True  # see parked.Builders
        self.empty_frames: list[Any] = []  # empty frames, deleted with the next bodies removed
        self.builders = mp.Builders()
        self.mj_spec.memory = ms.arena_bytes(1, 0)
        self.parts: set[str] = set()  # names of loaded models' links
        self.loaded_joints = Joints()
        self.wrenches = Wrenches()
        self.models = 0  # model entities alive
        self.broken = False
        # Bodies bound from or parked into the pool since the last compile: the compiled
        # model then differs from what its spec compiles to (see snapshot).
        self.parked_edited = False
        self.xml: str | None = None  # the spec as MJCF, kept until the spec changes
        ms.write_options(self.mj_spec.option, self.values)
        self.model = self.mj_spec.compile()
        self.data = mujoco.MjData(self.model)
        self.workers = 0  # a new MjData has no thread pool
        self.start_workers()
        self.reindex()

    def own(self) -> None:
        """Before changing the spec, the model or the records naming spec elements: its own
        copy of them if it shares them with a fork or a source (clone.own)."""
        if self.sharing is not None:
            cloning.own(self)

    def writable_model(self) -> mujoco.MjModel:
        """The model, its own (for an edit of its arrays)."""
        self.own()
        return self.model

    def recompile(self, nbody: int | None = None, nv: int | None = None) -> None:
        self.compile(nbody, nv)
        self.reindex()

    def compile(self, nbody: int | None = None, nv: int | None = None) -> None:
        self.own()
        compiling.compile_in_place(self, nbody, nv)

    def start_workers(self) -> None:
        """Size the current MjData's thread pool (a new MjData starts with none).

        Workers pay off only in a crowded world: always on, their hand-off made 100-ball
        trials 20 % slower, while 500-ball trials ran 6-16 % faster with them. So they run
        while the last step had at least WORKERS_ON_CONTACTS contacts, and stop below
        WORKERS_OFF_CONTACTS. Results are bit-identical either way.
        """
        wanted = self.values["mujoco.threads"] if self.crowded else 0
        if wanted != self.workers:
            mujoco.mju_threadpool(self.data, wanted)
            self.workers = wanted

    def track_crowding(self) -> None:
        ncon = self.data.ncon
        crowded = ncon >= WORKERS_ON_CONTACTS or (self.crowded and ncon >= WORKERS_OFF_CONTACTS)
        if crowded != self.crowded:
            self.crowded = crowded
            self.start_workers()

    def reindex(self) -> None:
        self.index = mst.StateIndex.of(self.model)
        self.sleep_guard = self.new_sleep_guard()
        self.ids = {name: e.body.id for name, e in self.entities.items()}
        self.watch: np.ndarray | None = None
        self.warnings = self.data.warning.number
        self.loaded_joints.reindex(self.model)
        self.loaded_joints.apply(self.model, self.data)
        self.wrenches.apply(self.data, self.ids)

    def new_sleep_guard(self) -> SleepGuard | None:
        """A guard for the compiled model, if wanted (see sleep_guard)."""
        return SleepGuard(self.model) if self.values["mujoco.wake_balanced"] else None

    def body_ids(self, names: Sequence[str]) -> np.ndarray:
        try:
            return np.fromiter((self.ids[n] for n in names), dtype=np.int64, count=len(names))
        except KeyError as exc:
            raise NotFoundError(f"no body named {exc.args[0]!r} in the MuJoCo world") from exc

    def geom_ids(self, names: Sequence[str]) -> np.ndarray:
        return compiling.geom_ids(self, names)

    def watched(self) -> np.ndarray:
        if self.watch is None:
            self.watch = compiling.watched_rows(self)
        return self.watch

    # -- Engine: description & parameters ------------------------------------------------
    @classmethod
    def engine_version(cls) -> str:
        return str(mujoco.__version__)

    def render_backend(self) -> str:
        return rendering.backend_name()

    @property
    def timestep(self) -> float:
        return float(self.model.opt.timestep)

    def get_params(self) -> dict[str, Any]:
        return {n: list(v) if isinstance(v, tuple) else v for n, v in self.values.items()}

    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, mparams.PARAMS, params)
        self.own()
        observing.freeze(self)
        self.xml = None
        self.values.update(clean)
        ms.write_options(self.mj_spec.option, self.values)
        ms.write_options(self.model.opt, self.values)
        if "mujoco.threads" in clean:
            self.start_workers()
        if "mujoco.wake_balanced" in clean:
            if self.sleep_guard is not None:
                self.sleep_guard.release_all(self.model)
            self.sleep_guard = self.new_sleep_guard()
        if mparams.CONTACT_PARAMS & clean.keys():
            for entity in self.entities.values():
                entity.key = None  # its values are rewritten: it no longer matches its kind
            self._apply_contacts(list(self.entities))

    def _apply_contacts(self, names: Sequence[str]) -> None:
        mpr.apply_contacts(self, names)

    def properties(self, names: Sequence[str]) -> np.ndarray:
        return mpr.properties(self, names)

    def free_bodies(self) -> int:
        """Free joints in the compiled model: what its compile is quadratic in."""
        return int(np.count_nonzero(self.model.jnt_type == mujoco.mjtJoint.mjJNT_FREE))

    # -- Engine: create & delete ---------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        for group in groups:
            check_group(group)
        observing.freeze(self)
        self.own()
        adding.spawn(self, groups)

    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str, *, fixed_base: bool = True) -> list[EntityInfo]:
        observing.freeze(self)
        self.own()
        return models.load_model(self, fmt, text, path, prefix, fixed_base)

    def delete(self, names: Sequence[str]) -> None:
        observing.freeze(self)
        self.own()
        removal.delete(self, names)

    def clear(self) -> None:
        self.own()
        removal.clear(self)

    # -- Engine: state --------------------------------------------------------------------
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        return mst.read_states(self.model, self.data, self.index, self.body_ids(names))

    def pose_reader(self, names: Sequence[str]) -> Callable[[], np.ndarray]:
        return PoseReader(self, names)

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        observing.freeze(self)
        self.own()
        teleport.set_states(self, names, poses, twists)

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        observing.freeze(self)
        self.own()
        self.xml = None
        mpr.update(self, names, props)

    # -- Engine: time (stepping) --------------------------------------------------------
    def step(self, count: int) -> None:
        timing.step(self, count)

    def look(self) -> None:
        timing.look(self)

    def state_within(self, max_position: float, max_speed: float) -> bool:
        return timing.state_within(self, max_position, max_speed)

    def reset_dynamics(self) -> None:
        self.own()  # the sleep guard gives back its sleep policies
        timing.reset_dynamics(self)

    def restart_looks(self) -> None:
        self.own()
        timing.restart_looks(self)

    # -- Engine: joints and wrenches (joints, wrench) ------------------------
    def joints(self) -> list[JointInfo]:
        return self.loaded_joints.describe()

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        positions, velocities, efforts = self.loaded_joints.read(self.data, names)
        return positions, velocities, observing.efforts(self, names, efforts)

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        """Written into qpos/qvel; a model's trees never sleep (their actuators keep them
        awake), so nothing needs waking."""
        observing.freeze(self)
        self.loaded_joints.write(self.data, names, positions, velocities)

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        self.own()  # the actuators' gains are model arrays
        self.loaded_joints.hold(self.model, self.data, names, mode, targets, kp, kd, max_effort)

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        self.own()  # dof_damping is a model array
        self.loaded_joints.set_damping(self.model, names, damping)

    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        wrench.set_wrenches(self, names, wrenches, points)

    def clear_wrenches(self, names: Sequence[str] | None) -> None:
        wrench.clear_wrenches(self, names)

    def restore_joints(self) -> None:
        self.own()
        wrench.restore_joints(self)

    # -- Engine: snapshots (snapshot) -----------------------------------------------
    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        """The whole world as plain data (``canonical`` makes no difference here); the
        promise: restore it into a fresh MuJoCo
        engine B (the same MuJoCo version), and this world A and B, given the same requests
        from then on (steps, spawns, deletes, teleports, targets, wrenches, parameters,
        updates), give the same states, joint states and properties bit for bit. A's state
        is untouched; but when bodies were bound from or parked into the pool since the
        last compile, A's model is first recompiled as its spec says (the data carried
        over exactly), so A goes on as B does, which may differ in the last bits from how
        it would have gone on without the snapshot. Mesh files named by the loaded models
        must still exist at restore."""
        self.own()  # an edited pool is recompiled first
        return snapshots.snapshot(self)

    def restore(self, data: dict[str, Any]) -> None:
        self.own()
        snapshots.restore(self, data)

    def entity_names(self) -> list[str]:
        return list(self.entities)

    def save_state(self) -> object | None:
        return fast_state.save(self)

    def load_state(self, state: object) -> bool:
        return fast_state.load(self, state)

    def recycle_state(self, state: object) -> None:
        fast_state.recycle(state)

    def clone(self) -> MujocoEngine:
        """A copy of the compiled world, no MJCF and no compile (``clone``): it goes
        on exactly as this one, which it leaves untouched."""
        return cloning.clone(self)

    # -- Engine: perception (render, perception) -------------------------------
    def render(self, cameras: Sequence[CameraView]
               ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
        return rendering.render(self, cameras)

    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
                ) -> RayHits:
        return RayHits(*sensing.cast_rays(self, origins, directions, max_length))

    def contacts(self, names: Sequence[str] | None
                 ) -> ContactPoints:
        return ContactPoints(*observing.contacts(self, names))

    def bounds(self, names: Sequence[str]) -> np.ndarray:
        """Each body's world box around its own geoms' boxes (MuJoCo's ``geom_aabb``, in
        the geom's frame); a body without geoms is a point at its origin."""
        model, data = self.model, self.data
        mujoco.mj_kinematics(model, data)  # positions only: the state is unchanged
        rows = np.empty((len(names), 6))
        for row, body in enumerate(self.body_ids(names)):
            geoms = np.flatnonzero(model.geom_bodyid == body)
            if not len(geoms):
                rows[row] = np.tile(data.xpos[body], 2)
                continue
            frames = data.geom_xmat[geoms].reshape(-1, 3, 3)
            local = model.geom_aabb[geoms]
            centres = data.geom_xpos[geoms] + np.einsum("nij,nj->ni", frames, local[:, :3])
            halves = np.einsum("nij,nj->ni", np.abs(frames), local[:, 3:])
            rows[row] = [*(centres - halves).min(axis=0), *(centres + halves).max(axis=0)]
        return rows

    def shapes(self, names: Sequence[str]) -> list[list[Shape]]:
        """Each body's colliding geoms in its frame (shapes.py)."""
        return colliders.body_shapes(self.model, self.body_ids(names).tolist())

    def shape_meshes(self, names: Sequence[str]) -> list[dict[int, ShapeMesh]]:
        """The triangles of each body's mesh geoms (shapes.py)."""
        return colliders.body_meshes(self.model, self.body_ids(names).tolist())

    def close(self) -> None:
        cloning.leave(self)
        self.entities = {}
        if self.workers == 0 and not self.broken and not self.closed:
            fast_state.give_back(self.model, self.data)  # to serve a fork or a snapshot
        self.closed = True
        if self.cameras is not None:
            self.cameras.close()
            self.cameras = None

