"""The MuJoCo engine: a world built with ``mujoco.MjSpec`` and edited while it runs.

A model load, and a delete that removes bodies, edit the spec and recompile it once, in
place (``MjSpec.recompile``), so the bodies already there keep their positions, velocities
and warm starts. A spawn does too unless the pool holds enough parked, pre-compiled bodies of
the group's kind: then it binds the names to them, no compile (``mujoco_pool``); a compiling
spawn adds spare parked twins, and delete and clear park spawned bodies again (no compile
when they all fit in the pool).

Dynamic bodies have a free joint; static ones are jointless children of the
world whose pose is written into the compiled model (and the spec), so moving them needs no
recompile, and balls resting on them can sleep (see ``mujoco_spec.add_group``). States are
read and written in batches through numpy index arrays (``mujoco_state``) rebuilt after each
compile: nothing in Python runs per body per step.

Contacts: a contact takes the larger of its two geoms' frictions and the average of their
solref (MuJoCo's rules); restitution maps to solref as ``mujoco_spec.damping_ratio`` says.

Every change is all or nothing. What can fail (a recompile MuJoCo rejects, a world MuJoCo
cannot hold) comes before anything that cannot; a failed recompile leaves the model and data
in use untouched, and the spec's edits and the engine's books are put back. Removed bodies
cannot be put back, so a delete in a world holding a loaded model (whose references may
reach other bodies) is first tried on a copy of the spec.

Size: MuJoCo holds at most ``mujoco_spec.MAX_BODIES`` bodies, and its compile costs
O(free bodies x degrees of freedom): about 1.6 s for 4,000 free spheres, four times that for
twice as many. Everything else here is linear in the bodies a call touches.
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
    GaltonError,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
    OperationFailedError,
    ResourceLimitError,
)

FEATURES = (FEATURE_SPAWN, FEATURE_DELETE, FEATURE_SET_STATE, FEATURE_UPDATE_MASS,
            FEATURE_UPDATE_FRICTION, FEATURE_UPDATE_RESTITUTION, FEATURE_UPDATE_RGBA,
            FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE)
_GEOM = mujoco.mjtObj.mjOBJ_GEOM
_BODY = mujoco.mjtObj.mjOBJ_BODY
# What MuJoCo raises for a model or a change it cannot take (FatalError: its mju_error).
_MUJOCO_ERRORS = (ValueError, TypeError, RuntimeError, mujoco.FatalError)
# Body names the engine keeps for itself: the world body's and the parked bodies'.
_WORLD = "world"


@dataclass(eq=False)
class _Entity:
    """An entity's spec body and what the engine must remember about it."""

    body: Any
    static: bool
    source: str = "spawn"
    friction: float | None = None
    restitution: float | None = None
    initial_pose: np.ndarray | None = None
    key: mp.Key | None = None  # its pool kind while its compiled values are still that kind's
    parts: tuple[str, ...] = ()  # a model entity's inner bodies' names (taken while it lives)

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


def _mujoco_error(exc: Exception, what: str) -> GaltonError:
    """A typed error for MuJoCo's refusal, in its words: too big is a resource limit."""
    words = str(exc)
    if "allocate memory" in words or "must be less than" in words:
        return ResourceLimitError(f"{what}: MuJoCo cannot hold the world ({words})")
    return InvalidArgumentError(f"{what}: {words}")


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
        self._spec.copy_during_attach = True  # see mujoco_spec.add_group
        self._home = self._spec.worldbody.add_frame()  # where big spawned groups live
        self._litter: list[Any] = []  # empty frames, deleted with the next bodies removed
        self._builders = mp.Builders()
        self._spec.memory = ms.arena_bytes(1, 0)
        self._parts: set[str] = set()  # names of loaded models' inner bodies
        self._models = 0  # model entities alive
        self._broken = False
        ms.write_options(self._spec.option, self._values)
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._workers = 0  # a new MjData has no thread pool
        self._start_workers()
        self._reindex()

    def _recompile(self, nbody: int | None = None, nv: int | None = None) -> None:
        self._compile(nbody, nv)
        self._reindex()

    def _compile(self, nbody: int | None = None, nv: int | None = None) -> None:
        """Compile the edited spec in place, keeping the state, with an arena for ``nbody``
        bodies and ``nv`` degrees of freedom (the model's own by default). On failure the
        model and data in use are untouched; raise with MuJoCo's words. (Reindex after.)"""
        m = self._model
        memory = self._spec.memory
        self._spec.memory = ms.arena_bytes(m.nbody if nbody is None else nbody,
                                           m.nv if nv is None else nv)
        try:
            self._model, self._data = self._spec.recompile(self._model, self._data)
        except _MUJOCO_ERRORS as exc:
            self._spec.memory = memory
            raise _mujoco_error(exc, "MuJoCo rejected the change") from exc
        self._workers = 0  # the recompiled MjData has no thread pool
        self._start_workers()

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
        self._watch: np.ndarray | None = None
        self._warnings = self._data.warning.number

    def _balance_guard(self) -> BalanceGuard | None:
        """A guard for the compiled model, if wanted (see mujoco_balance)."""
        return BalanceGuard(self._model) if self._values["mujoco.wake_balanced"] else None

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

    def _watched(self) -> np.ndarray:
        """qpos rows of the entities' free bodies' positions (parked ones are no entities)."""
        if self._watch is None:
            ids = np.fromiter(self._ids.values(), dtype=np.int64, count=len(self._ids))
            free = ids[self._index.kind[ids] == FREE]
            self._watch = (self._index.qadr[free][:, None] + np.arange(3)).ravel()
        return self._watch

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

    def properties(self, names: Sequence[str]) -> np.ndarray:
        """Mass from the compiled model (a model's subtree; NaN when static), the first geom's
        sliding friction, and the nominal restitution: the one given, the default a spawned
        body follows, NaN for a model's own contacts (MuJoCo has no restitution as such)."""
        m, ids = self._model, self._body_ids(names)
        entities = [self._entities[n] for n in names]
        spawned = np.array([e.source == "spawn" for e in entities], dtype=bool)
        mass = np.where(spawned, m.body_mass[ids], m.body_subtreemass[ids])
        mass[[e.static for e in entities]] = np.nan
        geoms = mst.first_geoms(m, ids, spawned)
        friction = np.where(geoms >= 0, m.geom_friction[np.maximum(geoms, 0), 0], np.nan)
        restitution = [self._restitution(e) for e in entities]
        return np.column_stack([mass, friction, np.array(restitution, dtype=float)])

    def _restitution(self, e: _Entity) -> float:
        if e.restitution is not None:
            return e.restitution
        if e.source == "spawn":
            return ms.default_surface(e.static, self._values)[1]
        return float("nan")

    def _free_bodies(self) -> int:
        """Free joints in the compiled model: what its compile is quadratic in."""
        return int(np.count_nonzero(self._model.jnt_type == mujoco.mjtJoint.mjJNT_FREE))

    # -- Engine: create & delete ---------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        """Bind parked bodies where the pool has enough of a group's kind; compile the other
        groups (with spare parked twins) in one recompile."""
        self._check_new([n for g in groups for n in g.names])
        pooled, compiled = self._pool.plan(groups, self._values, self._model.nbody,
                                           len(self._entities), self._free_bodies())
        if compiled:
            self._compile_groups(compiled)
        for group, key in pooled:
            self._bind(group, key)
        if pooled:
            mp.refresh(self._model, self._data)
        for group in groups:
            if group.twists is not None and not group.static:
                mst.write_twists(self._data, self._index, self._body_ids(group.names),
                                 np.asarray(group.twists, dtype=float), None)

    def _check_new(self, names: Sequence[str]) -> None:
        if len(set(names)) != len(names):
            raise InvalidArgumentError("MuJoCo rejected the change: a name is repeated")
        for name in names:
            if name in self._entities:
                raise NameNotUniqueError(f"an entity named {name!r} already exists")
            if name in self._parts:  # a model's inner link, which is no entity of the World's
                raise InvalidArgumentError(f"MuJoCo already has a body named {name!r} (a part "
                                           "of a loaded model); choose another name")
            if name == _WORLD or name.startswith(mp.PREFIX):
                raise InvalidArgumentError(f"the body name {name!r} is the MuJoCo engine's own "
                                           f"(the world, or beginning {mp.PREFIX!r})")

    def _compile_groups(self, compiled: Sequence[mp.Planned]) -> None:
        """Add the groups' bodies and spares, recompile; on any failure take them out."""
        snapshot = self._pool.snapshot()
        additions = mp.Additions(self._spec, self._home, self._builders)
        nbody, nv = self._model.nbody, self._model.nv
        try:
            for group, material, _, spares in compiled:
                additions.add(group, material)
                if spares:
                    additions.add(self._pool.spare_group(group, spares), material, parked=True)
                nbody += len(group) + spares
                nv += 0 if group.static else 6 * (len(group) + spares)
            self._compile(nbody, nv)
        except BaseException:
            self._pool.restore(snapshot)
            additions.undo()
            raise
        made = iter(additions.bodies())
        self._litter += additions.litter
        for group, _, key, spares in compiled:
            for name, body in zip(group.names, next(made), strict=True):
                self._entities[name] = _Entity(body, group.static, friction=group.friction,
                                               restitution=group.restitution, key=key)
            if spares:
                self._pool.adopt(key, next(made))
        self._reindex()

    def _bind(self, group: BodyGroup, key: mp.Key) -> None:
        """Give a group's names to parked bodies of its kind and release them: no compile."""
        bodies = self._pool.take(key, len(group))
        poses = np.asarray(group.poses, dtype=float)
        mp.bind_spec(bodies, group.names, poses)
        for name, body in zip(group.names, bodies, strict=True):
            self._entities[name] = _Entity(body, group.static, friction=group.friction,
                                           restitution=group.restitution, key=key)
            self._ids[name] = body.id
        self._watch = None
        mp.bind_arrays(self._model, self._data, self._index, self._body_ids(group.names),
                       poses)

    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str) -> list[EntityInfo]:
        if fmt != "mjcf":
            raise FeatureUnsupportedError(f"model format {fmt!r} is not supported by MuJoCo "
                                          "here; supported: mjcf")
        child = ms.parse_mjcf(text, path)
        tops, parts = ms.model_names(child, prefix)
        self._check_model_names([*tops, *(n for names in parts for n in names)])
        try:
            trial = self._spec.copy()  # attaching cannot be undone: try it on a copy first
            trial.attach(child.copy(), prefix=prefix, frame=trial.worldbody.add_frame())
            size = trial.compile()
        except _MUJOCO_ERRORS as exc:
            raise _mujoco_error(exc, "the MJCF model does not fit this world") from exc
        frame = self._spec.worldbody.add_frame()
        try:
            self._spec.attach(child, prefix=prefix, frame=frame)
            for name, inner in zip(tops, parts, strict=True):
                body = self._spec.body(name)
                self._entities[name] = _Entity(body, static=bool(body.mocap), source="model",
                                               parts=inner)
            self._recompile(size.nbody, size.nv)
        except (GaltonError, *_MUJOCO_ERRORS) as exc:
            for name in tops:
                self._entities.pop(name, None)
            mp.remove_frame(self._spec, frame)  # with the model's bodies and what uses them
            if isinstance(exc, GaltonError):
                raise
            raise _mujoco_error(exc, "the MJCF model does not fit this world") from exc
        self._models += len(tops)
        self._parts.update(n for names in parts for n in names)
        return [self._model_info(name) for name in tops]

    def _check_model_names(self, names: Sequence[str]) -> None:
        for name in names:
            if name in self._entities or name in self._parts or name == _WORLD or \
                    name.startswith(mp.PREFIX):
                raise NameNotUniqueError(
                    f"the model's body {name!r} has the name of a body already in the MuJoCo "
                    "world; load it with another prefix")

    def _model_info(self, name: str) -> EntityInfo:
        bid = self._ids[name]
        entity = self._entities[name]
        if self._index.kind[bid] == JOINTED:
            poses, _ = mst.jointed_states(self._model, self._data, np.array([bid]))
            entity.initial_pose = poses[0]
        return EntityInfo(name=name, shape="model", static=entity.static,
                          mass=float(self._model.body_subtreemass[bid]), source="model")

    def delete(self, names: Sequence[str]) -> None:
        """Spawned bodies still of their kind go back to the pool, parked (no compile while
        they all fit); the others leave the spec, and one recompile follows."""
        ids = self._body_ids(names)
        entities = [self._entities[n] for n in names]
        parked, removed = self._pool.split(entities)
        if removed and self._models:
            self._try_removing(removed)
        for name, entity in zip(names, entities, strict=True):
            self._forget(name, entity)
        if self._put_away(parked, removed):
            try:
                self._recompile()
            except GaltonError as exc:
                self._broken = True  # the bodies are out of the spec, not of the model
                raise OperationFailedError(
                    f"MuJoCo failed to recompile after a delete ({exc}); the world must be "
                    "reset") from exc
            park = np.array([e.body.id for e in parked], dtype=np.int64)
        else:
            chosen = {id(e) for e in parked}
            park = ids[[i for i, e in enumerate(entities) if id(e) in chosen]]
            if self._balance is not None:
                self._balance.forget(self._model, self._model.body_treeid[park])
        mp.park_arrays(self._model, self._data, self._index, park)

    def _put_away(self, parked: Sequence[_Entity], removed: Sequence[_Entity]) -> bool:
        """Park what the pool takes and take the rest out of the spec; whether a recompile
        must follow."""
        self._pool.park(parked)
        if removed:
            mp.remove_bodies(self._spec, [e.body for e in removed], self._sweep())
        return bool(removed) or self._gravcomp_missing(parked)

    def _forget(self, name: str, entity: _Entity) -> None:
        del self._entities[name]
        del self._ids[name]
        self._watch = None
        self._parts.difference_update(entity.parts)
        self._models -= entity.source == "model"

    def _sweep(self) -> list[Any]:
        """The litter (see mujoco_pool.Additions.bodies), handed over to be deleted."""
        litter, self._litter = self._litter, []
        return litter

    def _gravcomp_missing(self, parked: Sequence[_Entity]) -> bool:
        """Whether parking these needs a recompile: a model compiled without any gravity
        compensation ignores the body_gravcomp that holds parked bodies up."""
        return self._model.ngravcomp == 0 and not all(e.static for e in parked)

    def _try_removing(self, removed: Sequence[_Entity]) -> None:
        """Compile a copy of the spec without these bodies; raise, changing nothing, if
        MuJoCo refuses it."""
        trial = self._spec.copy()
        mp.remove_bodies(trial, [trial.body(e.body.name) for e in removed])
        try:
            trial.compile()
        except _MUJOCO_ERRORS as exc:
            raise _mujoco_error(exc, "MuJoCo cannot delete these bodies") from exc

    def clear(self) -> None:
        """An empty world at time 0; the pool stays warm: every spawned body is parked."""
        self._restart_looks()  # held balls get their sleep policy back: the model may stay
        entities = list(self._entities.values())
        self._entities.clear()
        self._diverged = False
        if self._models or self._broken:
            self._build_empty()  # a model may bring more than bodies: start afresh
            return
        parked, removed = self._pool.split(entities)
        if self._put_away(parked, removed):
            try:
                self._recompile()
            except GaltonError:
                self._build_empty()
                return
        mp.park_arrays(self._model, self._data, self._index,
                       np.array([e.body.id for e in parked], dtype=np.int64))
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
        for row in np.flatnonzero(jointed).tolist():
            mst.check_jointed(names[row], self._entities[names[row]].initial_pose,
                              None if poses is None else poses[row],
                              None if twists is None else twists[row])
        d = self._data
        if poses is not None and twists is None and free.any():
            # A pose alone keeps the world-frame twist: MuJoCo holds a free body's spin in
            # its own frame, so it is read first and written back after the turn.
            twists = np.zeros((len(ids), 6))
            twists[free] = mst.read_states(self._model, d, self._index, ids[free])[1]
        if poses is not None and free.any():
            mst.write_free_poses(d, self._index, ids[free], poses[free])
        if twists is not None and free.any():
            mst.write_twists(d, self._index, ids[free], twists[free],
                             None if poses is None else poses[free])
        if poses is not None and mocap.any():
            mst.write_mocap_poses(d, self._index, ids[mocap], poses[mocap])
        if poses is not None and static.any():
            self._move_static([names[i] for i in np.flatnonzero(static).tolist()], ids[static],
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
        """The mass first, the one change MuJoCo may refuse (its recompile); the rest
        cannot fail, so a refused mass leaves every property as it was."""
        self._body_ids(names)
        if props.mass is not None:
            self._set_masses(names, props.mass)
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

    def _set_masses(self, names: Sequence[str], mass: float) -> None:
        """Give each entity this total mass (a model's bodies scaled alike); one recompile,
        the spec's old values put back if MuJoCo refuses it."""
        m = self._model
        undo: list[tuple[Any, str, Any]] = []
        for name in names:
            entity = self._entities[name]
            if entity.source == "spawn":
                undo += ms.set_values(entity.body.first_geom(), mass=mass)
                continue
            scale = mass / max(float(m.body_subtreemass[self._ids[name]]), 1e-12)
            for body in [entity.body, *entity.body.find_all(_BODY)]:
                bid = body.id
                undo += ms.set_values(body, mass=float(m.body_mass[bid]) * scale,
                                      inertia=m.body_inertia[bid] * scale,
                                      ipos=m.body_ipos[bid], iquat=m.body_iquat[bid],
                                      explicitinertial=True)
        try:
            self._recompile()
        except GaltonError:
            for element, attribute, value in reversed(undo):
                setattr(element, attribute, value)
            raise

    # -- Engine: time ---------------------------------------------------------------------
    def step(self, count: int) -> None:
        """MuJoCo's own errors in a step (its arena overflowing) leave the data unusable:
        the world reads as diverged until cleared."""
        self._warnings[ms.DIVERGENCE_WARNINGS] = 0
        while count > 0:
            run = min(count, LOOK_EVERY_STEPS - self._steps_since_look)
            try:
                mujoco.mj_step(self._model, self._data, run)
            except mujoco.FatalError as exc:
                self._broken = True
                raise OperationFailedError(f"MuJoCo failed in a step ({exc}); the world "
                                           "must be reset") from exc
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

    def state_within(self, max_position: float, max_speed: float) -> bool:
        """numpy over qpos, qvel and mocap (see mujoco_state.within); MuJoCo's own warnings
        of a blow-up, or a world left half-changed by a failed delete, count as diverged."""
        if self._diverged or self._broken:
            return False
        return mst.within(self._data, self._index, self._watched(), max_position, max_speed)

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
