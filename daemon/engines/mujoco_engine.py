"""The MuJoCo engine: a world built with ``mujoco.MjSpec`` and edited while it runs.

Every delete or model load edits the spec and recompiles it once, in place
(``MjSpec.recompile``), so the bodies already there keep their positions, velocities and
warm starts. A spawn does too unless the pool holds enough parked, pre-compiled bodies of the
group's kind: then it binds the names to them, no compile (``mujoco_pool``); a compiling spawn
adds spare parked twins, and delete and clear park spawned bodies again.

Dynamic bodies have a free joint; static ones are jointless children of the
world whose pose is written into the compiled model (and the spec), so moving them needs no
recompile, and balls resting on them can sleep (see ``mujoco_spec.add_group``). States are
read and written in batches through numpy index arrays (``mujoco_state``) rebuilt after each
compile: nothing in Python runs per body per step.

Contacts: a contact takes the larger of its two geoms' frictions and the average of their
solref (MuJoCo's rules); restitution maps to solref as ``mujoco_spec.damping_ratio`` says.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import mujoco
import numpy as np

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
from galton.daemon.engines import mujoco_pool as mp
from galton.daemon.engines import mujoco_spec as ms
from galton.daemon.engines import mujoco_state as mst
from galton.daemon.engines.mujoco_balance import BalanceGuard
from galton.daemon.engines.mujoco_state import FREE, JOINTED, MOCAP, STATIC
from galton.daemon.params import check_updates
from galton.protocol import (
    BODY_SHAPES,
    PROTOCOL_VERSION,
    BodyGroup,
    BodyProperties,
    Capabilities,
    EntityInfo,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NotFoundError,
    OperationFailedError,
)

FEATURES = (FEATURE_SPAWN, FEATURE_DELETE, FEATURE_SET_STATE, FEATURE_UPDATE_MASS,
            FEATURE_UPDATE_FRICTION, FEATURE_UPDATE_RESTITUTION, FEATURE_UPDATE_RGBA,
            FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE)
_GEOM = mujoco.mjtObj.mjOBJ_GEOM


@dataclass
class _Entity:
    """An entity's spec body and what the engine must remember about it."""

    body: Any
    static: bool
    source: str = "spawn"
    friction: float | None = None
    restitution: float | None = None
    initial_pose: np.ndarray | None = None
    key: mp.Key | None = None  # its pool kind while its compiled values are still that kind's

    def geoms(self) -> list[Any]:
        return [self.body.first_geom()] if self.source == "spawn" else \
            self.body.find_all(_GEOM)


# Contacts at which MuJoCo's worker threads start helping, and below which they stop.
WORKERS_ON_CONTACTS = 400
WORKERS_OFF_CONTACTS = 200
# Steps of the world between two looks at the contact count and at balls asleep on a crown.
# Counted across requests, so the looks fall on the same steps however the steps are split
# into requests (a step(1) loop or one long run_until give the same trajectory).
LOOK_EVERY_STEPS = 50


class MujocoEngine(Engine):
    """A MuJoCo world of named bodies; see the module docstring for how it is kept."""

    name: ClassVar[str] = "mujoco"
    releases_gil_while_stepping: ClassVar[bool] = True  # mj_step runs without the GIL

    def __init__(self) -> None:
        ms.route_warnings()
        self._values: dict[str, Any] = {n: p.default for n, p in ms.PARAMS.items()}
        self._entities: dict[str, _Entity] = {}
        self._diverged = False
        self._crowded = False
        self._workers = 0
        self._steps_since_look = 0
        self._build_empty()

    # -- compile & index ----------------------------------------------------------------
    def _build_empty(self) -> None:
        self._pool = mp.Pool()
        self._spec = mujoco.MjSpec()
        self._spec.modelname = "galton"
        ms.write_options(self._spec.option, self._values)
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._workers = 0  # a new MjData has no thread pool
        self._start_workers()
        self._reindex()

    def _recompile(self) -> None:
        """Compile the edited spec in place, keeping the state; raise with MuJoCo's words."""
        try:
            self._model, self._data = self._spec.recompile(self._model, self._data)
        except ValueError as exc:
            raise InvalidArgumentError(f"MuJoCo rejected the change: {exc}") from exc
        self._workers = 0  # the recompiled MjData has no thread pool
        self._start_workers()
        self._reindex()

    def _start_workers(self) -> None:
        """Size the current MjData's thread pool (a new MjData starts with none).

        Workers pay off only in a crowded world: always on, their hand-off made 100-ball
        trials 20 % slower, while 500-ball trials ran 6-16 % faster with them. So they run
        while the last step had at least WORKERS_ON_CONTACTS contacts, and stop below
        WORKERS_OFF_CONTACTS. Results are bit-identical either way.
        """
        wanted = self._values["mujoco.threads"] if self._crowded else 0
        if wanted != self._workers:
            mujoco.mju_threadpool(self._data, wanted)
            self._workers = wanted

    def _track_crowding(self) -> None:
        ncon = self._data.ncon
        crowded = ncon >= WORKERS_ON_CONTACTS or (self._crowded and ncon >= WORKERS_OFF_CONTACTS)
        if crowded != self._crowded:
            self._crowded = crowded
            self._start_workers()

    def _reindex(self) -> None:
        self._index = mst.StateIndex.of(self._model)
        self._balance = self._balance_guard()
        self._ids = {name: e.body.id for name, e in self._entities.items()}
        self._warnings = self._data.warning.number

    def _balance_guard(self) -> BalanceGuard | None:
        """A guard for the compiled model, if wanted (see mujoco_balance)."""
        return BalanceGuard(self._model) if self._values["mujoco.wake_balanced"] else None

    def _commit(self, added: Sequence[str], spares: Sequence[Any] = ()) -> None:
        """Recompile after adding these entities (and parked spares); on failure take them
        out again."""
        try:
            self._recompile()
        except InvalidArgumentError:
            self._pool.forget(spares)
            ms.remove_bodies(self._spec, [*(self._entities.pop(n).body for n in added), *spares])
            raise

    def _body_ids(self, names: Sequence[str]) -> np.ndarray:
        try:
            return np.fromiter((self._ids[n] for n in names), dtype=np.int64, count=len(names))
        except KeyError as exc:
            raise NotFoundError(f"no body named {exc.args[0]!r} in the MuJoCo world") from exc

    def _geom_ids(self, names: Sequence[str]) -> np.ndarray:
        """Every geom of these entities: a spawned body's one, a model's whole subtree."""
        m = self._model
        ids = self._body_ids(names)
        spawned = np.fromiter((self._entities[n].source == "spawn" for n in names), dtype=bool,
                              count=len(names))
        gids = [m.body_geomadr[ids[spawned]]]
        if not spawned.all():
            gids.append(np.flatnonzero(np.isin(m.body_rootid[m.geom_bodyid], ids[~spawned])))
        return np.concatenate(gids)

    # -- Engine: description & parameters ------------------------------------------------
    def capabilities(self) -> Capabilities:
        return Capabilities(
            engine=self.name, engine_version=mujoco.__version__,
            protocol_version=PROTOCOL_VERSION, body_shapes=tuple(BODY_SHAPES),
            model_formats=("mjcf",), features=FEATURES,
            params={n: p.describe() for n, p in ms.PARAMS.items()})

    @property
    def timestep(self) -> float:
        return float(self._model.opt.timestep)

    def get_params(self) -> dict[str, Any]:
        return {n: list(v) if isinstance(v, tuple) else v for n, v in self._values.items()}

    def set_params(self, params: dict[str, Any]) -> None:
        clean = check_updates(self.name, ms.PARAMS, params)
        self._values.update(clean)
        ms.write_options(self._spec.option, self._values)
        ms.write_options(self._model.opt, self._values)
        if "mujoco.threads" in clean:
            self._start_workers()
        if "mujoco.wake_balanced" in clean:
            if self._balance is not None:
                self._balance.release_all(self._model)
            self._balance = self._balance_guard()
        if ms.CONTACT_PARAMS & clean.keys():
            for entity in self._entities.values():
                entity.key = None  # its values are rewritten: it no longer matches its kind
            self._apply_contacts(list(self._entities))

    def _apply_contacts(self, names: Sequence[str]) -> None:
        """Write these entities' contact values into the model and the spec: friction
        (sliding, torsional, rolling), condim, solref, solimp.

        Spawned bodies follow the defaults where they were given none; a loaded model keeps
        its file's values except those set by ``update``.
        """
        m, v = self._model, self._values
        for name in names:
            e = self._entities[name]
            spawned = e.source == "spawn"
            default_friction, default_restitution = ms.default_surface(e.static, v)
            friction = default_friction if e.friction is None and spawned else e.friction
            restitution = default_restitution if e.restitution is None and spawned \
                else e.restitution
            if friction is None and restitution is None:
                continue
            ms.write_contacts(m, e.geoms(), self._geom_ids([name]), v, friction, restitution,
                              spawned)

    # -- Engine: create & delete ---------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        """Bind parked bodies where the pool has enough of a group's kind; compile the other
        groups (with spare parked twins) in one recompile."""
        names = [n for g in groups for n in g.names]
        taken = [n for n in names if self._spec.body(n) is not None]
        if taken:  # a model's inner link, which is no entity of the World's
            raise InvalidArgumentError(f"MuJoCo already has a body named {taken[0]!r} (a part "
                                       "of a loaded model); choose another name")
        if len(set(names)) != len(names):
            raise InvalidArgumentError("MuJoCo rejected the change: a name is repeated")
        added: list[str] = []
        spares: list[Any] = []
        pooled: list[tuple[BodyGroup, mp.Key]] = []
        wanted: dict[mp.Key, int] = {}
        for group in groups:
            material = ms.material(group, self._values)
            key = mp.key_of(group, material)
            if self._pool.available(key) >= wanted.get(key, 0) + len(group):
                wanted[key] = wanted.get(key, 0) + len(group)
                pooled.append((group, key))
                continue
            for name, body in ms.add_group(self._spec, group, material):
                self._entities[name] = _Entity(body, group.static, friction=group.friction,
                                               restitution=group.restitution, key=key)
                added.append(name)
            spares += self._pool.add_spares(self._spec, group, material, key,
                                            self._pool.spares(len(group)))
        if added:
            self._commit(added, spares)
        for group, key in pooled:
            self._bind(group, key)
        if pooled:
            mp.refresh(self._model, self._data)
        for group in groups:
            if group.twists is not None and not group.static:
                mst.write_twists(self._data, self._index, self._body_ids(group.names),
                                 np.asarray(group.twists, dtype=float), None)

    def _bind(self, group: BodyGroup, key: mp.Key) -> None:
        """Give a group's names to parked bodies of its kind and release them: no compile."""
        bodies = self._pool.take(key, len(group))
        poses = np.asarray(group.poses, dtype=float)
        mp.bind_spec(bodies, group.names, poses)
        for name, body in zip(group.names, bodies, strict=True):
            self._entities[name] = _Entity(body, group.static, friction=group.friction,
                                           restitution=group.restitution, key=key)
            self._ids[name] = body.id
        mp.bind_arrays(self._model, self._data, self._index, self._body_ids(group.names),
                       poses)

    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str) -> list[EntityInfo]:
        if fmt != "mjcf":
            raise FeatureUnsupportedError(f"model format {fmt!r} is not supported by MuJoCo "
                                          "here; supported: mjcf")
        child = ms.parse_mjcf(text, path)
        names = [prefix + body.name for body in child.worldbody.bodies]
        trial = self._spec.copy()  # attaching cannot be undone: try it on a copy first
        try:
            trial.attach(child.copy(), prefix=prefix, frame=trial.worldbody.add_frame())
            trial.compile()
        except ValueError as exc:
            raise InvalidArgumentError(f"the MJCF model does not fit this world: {exc}") from exc
        self._spec.attach(child, prefix=prefix, frame=self._spec.worldbody.add_frame())
        for name in names:
            body = self._spec.body(name)
            self._entities[name] = _Entity(body, static=bool(body.mocap), source="model")
        self._commit(names)
        return [self._model_info(name) for name in names]

    def _model_info(self, name: str) -> EntityInfo:
        bid = self._ids[name]
        entity = self._entities[name]
        if self._index.kind[bid] == JOINTED:
            poses, _ = mst.jointed_states(self._model, self._data, np.array([bid]))
            entity.initial_pose = poses[0]
        return EntityInfo(name=name, shape="model", static=entity.static,
                          mass=float(self._model.body_subtreemass[bid]), source="model")

    def delete(self, names: Sequence[str]) -> None:
        """One recompile; spawned bodies still of their kind go back to the pool, parked."""
        self._body_ids(names)
        parked = self._pool.park_or_remove(self._spec, [self._entities.pop(n) for n in names])
        try:
            self._recompile()
        except InvalidArgumentError as exc:
            raise OperationFailedError(f"MuJoCo failed to recompile after a delete: {exc}") \
                from exc
        mp.park_arrays(self._model, self._data, self._index, parked)

    def clear(self) -> None:
        """An empty world at time 0; the pool stays warm: every spawned body is parked."""
        self._restart_looks()  # held balls get their sleep policy back: the model may stay
        entities = list(self._entities.values())
        self._entities.clear()
        self._diverged = False
        if any(e.source != "spawn" for e in entities):
            self._build_empty()  # a model may bring more than bodies: start afresh
            return
        parked = self._pool.park_or_remove(self._spec, entities)
        if len(parked) < len(entities) or (  # removed some; or gravcomp was compiled out
                self._model.ngravcomp == 0 and not all(e.static for e in entities)):
            self._recompile()
        mp.park_arrays(self._model, self._data, self._index, parked)
        mujoco.mj_resetData(self._model, self._data)
        self._reindex()

    # -- Engine: state --------------------------------------------------------------------
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        return mst.read_states(self._model, self._data, self._index, self._body_ids(names))

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        ids = self._body_ids(names)
        kind = self._index.kind[ids]
        free, mocap, jointed = kind == FREE, kind == MOCAP, kind == JOINTED
        static = kind == STATIC
        poses = None if poses is None else np.asarray(poses, dtype=float)
        twists = None if twists is None else np.asarray(twists, dtype=float)
        fixed = mocap | static
        if twists is not None and np.any(twists[fixed]):
            bad = names[int(np.flatnonzero(fixed & np.any(twists, axis=1))[0])]
            raise InvalidArgumentError(f"entity {bad!r} is static: it cannot be given a "
                                       "non-zero twist")
        for row in np.flatnonzero(jointed):
            mst.check_jointed(names[row], self._entities[names[row]].initial_pose,
                              None if poses is None else poses[row],
                              None if twists is None else twists[row])
        d = self._data
        if poses is not None and free.any():
            mst.write_free_poses(d, self._index, ids[free], poses[free])
        if twists is not None and free.any():
            mst.write_twists(d, self._index, ids[free], twists[free],
                             None if poses is None else poses[free])
        if poses is not None and mocap.any():
            mst.write_mocap_poses(d, self._index, ids[mocap], poses[mocap])
        if poses is not None and static.any():
            self._move_static([names[i] for i in np.flatnonzero(static)], ids[static],
                              poses[static])
        if poses is not None and fixed.any():
            mst.wake_all(self._model, d)
        if jointed.any():
            mst.reset_joints(self._model, d, ids[jointed])

    def _move_static(self, names: Sequence[str], ids: np.ndarray, poses: np.ndarray) -> None:
        """Pose static bodies in the compiled model and in the spec (kept by recompiles)."""
        quats = mst.to_wxyz(poses[:, 3:])
        self._model.body_pos[ids] = poses[:, :3]
        self._model.body_quat[ids] = quats
        for row, name in enumerate(names):
            body = self._entities[name].body
            body.pos = poses[row, :3]
            body.quat = quats[row]

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        self._body_ids(names)
        for name in names:
            entity = self._entities[name]
            entity.key = None  # no longer like its parked twins: deleting it removes it
            if props.friction is not None:
                entity.friction = props.friction
            if props.restitution is not None:
                entity.restitution = props.restitution
        if props.friction is not None or props.restitution is not None:
            self._apply_contacts(names)
        if props.rgba is not None:
            self._model.geom_rgba[self._geom_ids(names)] = props.rgba
            for name in names:
                for geom in self._entities[name].geoms():
                    geom.rgba = props.rgba
        if props.mass is not None:
            self._set_masses(names, props.mass)

    def _set_masses(self, names: Sequence[str], mass: float) -> None:
        """Give each entity this total mass (a model's bodies scaled alike); one recompile."""
        m = self._model
        for name in names:
            entity = self._entities[name]
            if entity.source == "spawn":
                entity.body.first_geom().mass = mass
                continue
            scale = mass / max(float(m.body_subtreemass[self._ids[name]]), 1e-12)
            for body in [entity.body, *entity.body.find_all(mujoco.mjtObj.mjOBJ_BODY)]:
                bid = body.id
                body.mass = float(m.body_mass[bid]) * scale
                body.inertia = m.body_inertia[bid] * scale
                body.ipos = m.body_ipos[bid]
                body.iquat = m.body_iquat[bid]
                body.explicitinertial = True
        self._recompile()

    # -- Engine: time ---------------------------------------------------------------------
    def step(self, count: int) -> None:
        self._warnings[ms.DIVERGENCE_WARNINGS] = 0
        while count > 0:
            run = min(count, LOOK_EVERY_STEPS - self._steps_since_look)
            mujoco.mj_step(self._model, self._data, run)
            count -= run
            self._steps_since_look += run
            if self._steps_since_look == LOOK_EVERY_STEPS:
                self._look()
        self._diverged |= bool(self._warnings[ms.DIVERGENCE_WARNINGS].any())

    def _look(self) -> None:
        """The periodic look: worker threads for a crowd, balls balanced on a crown. It
        costs about 40 µs, twice a small world's step, so never once per step."""
        self._steps_since_look = 0
        self._track_crowding()
        if self._balance is not None:
            self._balance.check(self._model, self._data)

    def state_is_finite(self) -> bool:
        d = self._data
        return not self._diverged and all(
            np.isfinite(a).all() for a in (d.qpos, d.qvel, d.mocap_pos, d.mocap_quat))

    def reset_dynamics(self) -> None:
        """Forget warm starts; also clear what a divergence left beyond the entities' roots."""
        m, d = self._model, self._data
        bad = ~np.isfinite(d.qpos)
        d.qpos[bad] = m.qpos0[bad]
        d.qvel[~np.isfinite(d.qvel)] = 0.0
        d.qacc_warmstart[:] = 0.0
        d.qacc[:] = 0.0
        mst.wake_all(m, d)
        self._diverged = False
        self._restart_looks()

    def _restart_looks(self) -> None:
        """The periodic looks start over, with a fresh balance guard: a rewound or cleared
        world replays its trajectory exactly."""
        self._steps_since_look = 0
        if self._balance is not None:
            self._balance.release_all(self._model)
            self._balance = self._balance_guard()

    def close(self) -> None:
        self._entities.clear()
