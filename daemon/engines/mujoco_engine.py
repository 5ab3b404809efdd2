"""The MuJoCo engine: a world built with ``mujoco.MjSpec`` and edited while it runs.

Every spawn, delete or model load edits the spec and recompiles it once, in place
(``MjSpec.recompile``), so the bodies already there keep their positions, velocities and
warm starts. Dynamic bodies have a free joint; static ones are jointless children of the
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
from galton.daemon.engines import mujoco_spec as ms
from galton.daemon.engines import mujoco_state as mst
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
# How far a jointed body's requested pose may be from its initial one (m, quaternion units).
_SAME_POSE = 1e-6
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

    def geoms(self) -> list[Any]:
        return [self.body.first_geom()] if self.source == "spawn" else \
            self.body.find_all(_GEOM)


class MujocoEngine(Engine):
    """A MuJoCo world of named bodies; see the module docstring for how it is kept."""

    name: ClassVar[str] = "mujoco"

    def __init__(self) -> None:
        ms.route_warnings()
        self._values: dict[str, Any] = {n: p.default for n, p in ms.PARAMS.items()}
        self._entities: dict[str, _Entity] = {}
        self._diverged = False
        self._build_empty()

    # -- compile & index ----------------------------------------------------------------
    def _build_empty(self) -> None:
        self._spec = mujoco.MjSpec()
        self._spec.modelname = "galton"
        ms.write_options(self._spec.option, self._values)
        self._model = self._spec.compile()
        self._data = mujoco.MjData(self._model)
        self._reindex()

    def _recompile(self) -> None:
        """Compile the edited spec in place, keeping the state; raise with MuJoCo's words."""
        try:
            self._model, self._data = self._spec.recompile(self._model, self._data)
        except ValueError as exc:
            raise InvalidArgumentError(f"MuJoCo rejected the change: {exc}") from exc
        self._reindex()

    def _reindex(self) -> None:
        self._index = mst.StateIndex.of(self._model)
        self._ids = {name: e.body.id for name, e in self._entities.items()}
        self._warnings = self._data.warning.number

    def _commit(self, added: Sequence[str]) -> None:
        """Recompile after adding these entities; on failure take them out again."""
        try:
            self._recompile()
        except InvalidArgumentError:
            self._remove_from_spec([self._entities.pop(n).body for n in added])
            raise

    def _remove_from_spec(self, bodies: Sequence[Any]) -> None:
        """Delete bodies from the spec in one go: gathered under one frame, then it deleted.

        (Deleting bodies one at a time copies the whole spec each time: 12 ms per body at
        1,000 bodies; deleting one frame holding them all costs one copy.)
        """
        frame = self._spec.worldbody.add_frame()
        for body in bodies:
            body.set_frame(frame)
        self._spec.delete(frame)

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
        if ms.CONTACT_PARAMS & clean.keys():
            self._apply_contacts(list(self._entities))

    def _apply_contacts(self, names: Sequence[str]) -> None:
        """Write these entities' contact values into the model and the spec: friction
        (sliding, torsional, rolling), condim, solref, solimp.

        Spawned bodies follow the defaults where they were given none; a loaded model keeps
        its file's values except those set by ``update``.
        """
        m, v = self._model, self._values
        solimp, spin = v["mujoco.solimp"], ms.spin_friction(v)
        for name in names:
            e = self._entities[name]
            spawned = e.source == "spawn"
            friction = v["default_friction"] if e.friction is None and spawned else e.friction
            restitution = v["default_restitution"] if e.restitution is None and spawned \
                else e.restitution
            if friction is None and restitution is None:
                continue
            gids = self._geom_ids([name])
            solref = None if restitution is None else ms.contact_solref(restitution, v)
            if friction is not None:
                m.geom_friction[gids, 0] = friction
            if solref is not None:
                m.geom_solref[gids] = solref
            if spawned:
                m.geom_solimp[gids] = solimp
                m.geom_friction[gids, 1:] = spin
                m.geom_condim[gids] = v["mujoco.condim"]
            for geom in e.geoms():
                if friction is not None:
                    geom.friction[0] = friction
                if solref is not None:
                    geom.solref = solref
                if spawned:
                    geom.solimp = solimp
                    geom.friction[1:] = spin
                    geom.condim = v["mujoco.condim"]

    # -- Engine: create & delete ---------------------------------------------------------
    def _material(self, group: BodyGroup) -> ms.Material:
        v = self._values
        friction = v["default_friction"] if group.friction is None else group.friction
        restitution = v["default_restitution"] if group.restitution is None \
            else group.restitution
        return ms.Material(friction=friction, spin=ms.spin_friction(v),
                           condim=v["mujoco.condim"], solref=ms.contact_solref(restitution, v),
                           solimp=tuple(v["mujoco.solimp"]), rgba=group.rgba, mass=group.mass)

    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        taken = [n for g in groups for n in g.names if self._spec.body(n) is not None]
        if taken:  # a model's inner link, which is no entity of the World's
            raise InvalidArgumentError(f"MuJoCo already has a body named {taken[0]!r} (a part "
                                       "of a loaded model); choose another name")
        added: list[str] = []
        for group in groups:
            for name, body in ms.add_group(self._spec, group, self._material(group)):
                self._entities[name] = _Entity(body, group.static, friction=group.friction,
                                               restitution=group.restitution)
                added.append(name)
        self._commit(added)
        for group in groups:
            if group.twists is not None and not group.static:
                mst.write_twists(self._data, self._index, self._body_ids(group.names),
                                 np.asarray(group.twists, dtype=float), None)

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
        self._body_ids(names)
        self._remove_from_spec([self._entities.pop(n).body for n in names])
        try:
            self._recompile()
        except InvalidArgumentError as exc:
            raise OperationFailedError(f"MuJoCo failed to recompile after a delete: {exc}") \
                from exc

    def clear(self) -> None:
        self._entities.clear()
        self._diverged = False
        self._build_empty()

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
            self._check_jointed(names[row], None if poses is None else poses[row],
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

    def _check_jointed(self, name: str, pose: np.ndarray | None,
                       twist: np.ndarray | None) -> None:
        """A body held by joints can only be put back, at rest, where it was loaded."""
        initial = self._entities[name].initial_pose
        moved = pose is not None and initial is not None and not (
            np.allclose(pose[:3], initial[:3], atol=_SAME_POSE)
            and abs(abs(float(pose[3:] @ initial[3:])) - 1) < _SAME_POSE)
        if moved or (twist is not None and np.any(twist)):
            raise FeatureUnsupportedError(
                f"entity {name!r} is held by joints of its model: it can only be reset to its "
                "initial pose at rest, not teleported")

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        self._body_ids(names)
        for name in names:
            entity = self._entities[name]
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
        mujoco.mj_step(self._model, self._data, count)
        self._diverged |= bool(self._warnings[ms.DIVERGENCE_WARNINGS].any())

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

    def close(self) -> None:
        self._entities.clear()
