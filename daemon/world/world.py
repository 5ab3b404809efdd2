"""The World: one engine's named entities (its scene), with the clock and the step counter.

The World checks every request against the registry before the engine sees it, so an
engine never receives an unknown or duplicate name, and a rejected request changes nothing.
"""

from __future__ import annotations

import contextlib
import dataclasses
import fnmatch
import math
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from galton.daemon.core.limits import DEFAULT_LIMITS, Limits
from galton.daemon.engines.base import Engine
from galton.daemon.engines.geometry import DENSITY, default_mass
from galton.daemon.world.joints import JointTable
from galton.daemon.world.model_files import resolve_model
from galton.daemon.world.surprise import SurpriseStreak
from galton.daemon.world.wrenches import WrenchSchedule
from galton.protocol import (
    POSE_WIDTH,
    RESET_SCOPES,
    TWIST_WIDTH,
    BodyGroup,
    BodyProperties,
    EntityInfo,
    InvalidArgumentError,
    NameNotUniqueError,
    PhysicsError,
    ResourceLimitError,
)
from galton.protocol.errors import brief, did_you_mean, unknown_names
from galton.protocol.model import check_type
from galton.protocol.vocabulary import ENTITY_KINDS, MIN_MASS

# A spawned mesh's triangles as spawn gave them: (n, 3) vertices in the body's frame,
# (m, 3) vertex indices. The bodies of one group share one pair (read-only arrays).
Mesh = tuple[np.ndarray, np.ndarray]


@dataclass
class Entity:
    """A registry entry: what the entity is, and the state it was created with (and a
    spawned mesh's triangles, kept so that ``get_shapes`` tells them on any engine)."""

    info: EntityInfo
    initial_pose: np.ndarray
    initial_twist: np.ndarray
    mesh: Mesh | None = None


def frozen_mesh(vertices: np.ndarray | None, faces: np.ndarray | None) -> Mesh | None:
    """Read-only copies of a mesh's arrays (None for a primitive)."""
    if vertices is None or faces is None:
        return None
    kept = (np.array(vertices, dtype=float).reshape(-1, 3),
            np.array(faces, dtype=np.int64).reshape(-1, 3))
    for array in kept:
        array.setflags(write=False)
    return kept


DEFAULT_SECONDS_PER_PIXEL = 1e-7  # before any render is measured: 10 Mpixel/s
# Renders whose measures make the estimate: their median, so that a one-off slow render
# (a renderer's context made for a new size: 1.4 s on MuJoCo) does not move it, while an
# engine slower than the default shows after three renders.
RENDER_SAMPLES = 5


class World:
    """One simulated world: an engine, its entities by name, and its clock."""

    def __init__(self, engine: Engine, name: str = "default",
                 limits: Limits = DEFAULT_LIMITS) -> None:
        self.engine = engine
        self.name = name
        self.limits = limits
        self.entities: dict[str, Entity] = {}
        self.step_index = 0
        self.faulted = False
        self.fault_cause = ""
        self.verified_step = 0  # the last step whose state was checked finite
        self.teleported = False  # a request set states since the last check
        self._time_base = (0, 0.0, engine.timestep)  # (step, sim time, dt) since dt changed
        self.joints = JointTable(engine)
        self.cameras: dict[str, Any] = {}  # named cameras (daemon/world/cameras.py Camera)
        # What one pixel of a render (and its encoding) costs the physics thread: the last
        # few renders' measures (ops/perception.py), whose median a render is costed at.
        self.render_costs: deque[float] = deque([DEFAULT_SECONDS_PER_PIXEL] * RENDER_SAMPLES,
                                                maxlen=RENDER_SAMPLES)
        self.wrenches = WrenchSchedule()
        # Counts changes of which entities the engine holds (a state stream's cached reader
        # of its names is good while this stays the same).
        self.layout = 0
        # Who the world's structure is (bodies, shapes, joints, parameters): a new object at
        # every change of it, shared with a clone until either changes. A state kept with
        # ``save_state`` loads again without a rebuild while this stays the same.
        self.structure: object = object()
        # compare's surprise trigger: its comparisons in a row above the threshold
        self.surprise = SurpriseStreak()

    # -- lookup -------------------------------------------------------------------------
    def require_known(self, names: Sequence[str]) -> None:
        """Raise NotFound naming the first unknown name (with a "did you mean")."""
        missing = [n for n in names if n not in self.entities]
        if missing:
            raise unknown_names("entity", missing, self.entities)

    def require_new(self, names: Sequence[str]) -> None:
        taken = [n for n in names if n in self.entities]
        if taken:
            more = f" and {len(taken) - 1} more" if len(taken) > 1 else ""
            raise NameNotUniqueError(
                f"an entity named {taken[0]!r}{more} already exists; delete it first or "
                "choose another name",
                {"taken": taken[:100], "taken_count": len(taken)},
            )

    def select(self, pattern: str | None = None, tag: str | None = None,
               kind: str | None = None) -> list[EntityInfo]:
        """Entities whose name matches a glob, that carry a tag, of a kind (static/dynamic)."""
        if kind is not None and kind not in ENTITY_KINDS:
            raise InvalidArgumentError(f"kind must be one of {ENTITY_KINDS}, got {brief(kind)}")
        found = []
        for name, entity in self.entities.items():
            if pattern is not None and not fnmatch.fnmatchcase(name, pattern):
                continue
            if tag is not None and tag not in entity.info.tags:
                continue
            if kind is not None and entity.info.static != (kind == "static"):
                continue
            found.append(entity.info)
        return found

    def require_room(self, count: int) -> None:
        """Refuse, before any work, a request that would take the world past its limit."""
        limit = self.limits.max_entities
        if len(self.entities) + count > limit:
            raise ResourceLimitError(
                f"the world holds {len(self.entities)} entities; {count} more would pass its "
                f"limit of {limit} (galton-daemon --limit max_entities=N)",
                {"limit": "max_entities", "max": limit, "count": len(self.entities)})

    def effective(self, infos: Sequence[EntityInfo]) -> list[EntityInfo]:
        """Copies of these entities' infos with the mass, friction and restitution the
        engine simulates (defaults included; a static body's mass stays None: it has none)."""
        if not infos:
            return []
        values = self.engine.properties([info.name for info in infos])
        return [dataclasses.replace(
            info, mass=_number_or_none(mass), friction=_number_or_none(friction),
            restitution=_number_or_none(restitution))
            for info, (mass, friction, restitution) in zip(infos, values.tolist(), strict=True)]

    # -- create / delete ----------------------------------------------------------------
    def spawn(self, groups: Sequence[BodyGroup]) -> list[str]:
        names = [n for g in groups for n in g.names]
        if len(set(names)) != len(names):
            raise InvalidArgumentError("the request names the same entity in two groups")
        self.require_new(names)
        for group in groups:
            _require_massive(group)
        self.layout += 1
        self.structure = object()
        for group in (g for g in groups if not g.static):  # a static body cannot diverge
            check_state_values(self.limits, group.poses, group.twists, "spawn")
        self.engine.spawn(groups)
        for group in groups:
            twists = group.twists if group.twists is not None else np.zeros(
                (len(group), TWIST_WIDTH))
            mesh = frozen_mesh(group.vertices, group.faces)
            for i, name in enumerate(group.names):
                info = EntityInfo(name=name, shape=group.shape, size=group.size,
                                  static=group.static, tags=group.tags, mass=group.mass,
                                  friction=group.friction, restitution=group.restitution)
                self.entities[name] = Entity(info, group.poses[i].copy(), twists[i].copy(),
                                             mesh)
        return names

    def load_model(self, fmt: str, text: str | None, path: str | None, prefix: str, *,
                   fixed_base: bool = True, search: Sequence[Path] = ()) -> list[str]:
        """Load a model's roots and links as entities (the files it names made absolute
        first, daemon/world/model_files.py); its joints join the joint table."""
        if text is None:
            assert path is not None
            text = Path(path).read_text(encoding="utf-8", errors="replace")
        text = resolve_model(fmt, text, path, search)
        self.layout += 1
        self.structure = object()
        infos = self.engine.load_model(fmt, text, path, prefix, fixed_base=fixed_base)
        names = [info.name for info in infos]
        try:
            self.require_room(len(names))
        except ResourceLimitError:
            self.engine.delete([info.name for info in infos if info.shape != "link"])
            raise
        poses, twists = self.engine.get_states(names) if names else (
            np.zeros((0, POSE_WIDTH)), np.zeros((0, TWIST_WIDTH)))
        for i, info in enumerate(infos):
            self.entities[info.name] = Entity(info, poses[i].copy(), twists[i].copy())
        self.joints.refresh()
        return names

    def delete(self, names: Sequence[str]) -> None:
        """Delete entities; a model goes whole, by its root (its links with it)."""
        self.require_known(names)
        self.require_no_links(names, "delete", "a link is deleted with its model")
        self.layout += 1
        self.structure = object()
        self.engine.delete(names)
        roots = {n for n in names if self.entities[n].info.shape == "model"}
        gone = [*names, *(n for n, e in self.entities.items()
                          if e.info.model in roots and n not in roots)]
        for name in gone:
            del self.entities[name]
        self.wrenches.forget(gone)
        if roots:
            self.joints.refresh()

    def require_no_links(self, names: Sequence[str], where: str, why: str) -> None:
        """Refuse a request that would act on a model's link alone."""
        for name in names:
            info = self.entities[name].info
            if info.shape == "link":
                raise InvalidArgumentError(
                    f"{where}: {name!r} is a link of model {info.model!r}: {why} (act on "
                    f"{info.model!r}, or on its joints)", {"model": info.model})

    # -- state --------------------------------------------------------------------------
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        self.require_known(names)
        self.verify()
        poses, twists = self.engine.get_states(names)
        return canonical_quaternions(poses), twists

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        self.require_known(names)
        self.require_no_links(names, "set_states", "a link moves with its joints")
        if twists is not None:
            static = [n for i, n in enumerate(names)
                      if self.entities[n].info.static and np.any(twists[i])]
            if static:
                raise InvalidArgumentError(
                    f"entity {static[0]!r} is static: it cannot be given a non-zero twist")
        moving = np.array([not self.entities[n].info.static for n in names], dtype=bool)
        check_state_values(self.limits, None if poses is None else poses[moving],
                           None if twists is None else twists[moving], "set_states")
        if poses is not None and not moving.all():
            self.structure = object()  # a static body's pose is part of the structure
        if self.faulted:  # nothing is read from it until a reset
            self.engine.set_states(names, poses, twists)
            return
        self.verify()  # steps not yet checked are checked first: their fault is theirs
        old_poses, old_twists = self.engine.get_states(names)
        self.engine.set_states(names, poses, twists)
        self._keep_or_undo("set_states", lambda: self.engine.set_states(
            names, None if poses is None else old_poses, None if twists is None else old_twists))

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        """Set checked 1-DOF joints' positions (and velocities) of a valid world; a state
        beyond the world's limits is refused and put back (never served, never faulting)."""
        self.verify()
        if velocities is not None:
            check_state_values(self.limits, None, np.repeat(velocities[:, None], 6, axis=1),
                               "set_joint_states.velocities")
        old_positions, old_velocities, _ = self.engine.get_joint_states(names)
        self.engine.set_joint_states(names, positions, velocities)
        self._keep_or_undo("set_joint_states", lambda: self.engine.set_joint_states(
            names, old_positions, old_velocities))

    def _keep_or_undo(self, where: str, undo: Callable[[], None]) -> None:
        """Keep the states a request just set when they are within the world's limits;
        else put the old ones back and refuse: a read never faults the world."""
        if self.engine.state_within(self.limits.max_position, self.limits.max_speed):
            return
        undo()
        raise InvalidArgumentError(
            f"{where}: the states it sets put a body beyond {self.limits.max_position:g} m "
            f"or {self.limits.max_speed:g} m/s (the world's limits); nothing was changed",
            {"max_position": self.limits.max_position, "max_speed": self.limits.max_speed})

    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        self.require_known(names)
        self.require_no_links(names, "update", "a model is updated as a whole")
        if props.mass is not None:
            static = [n for n in names if self.entities[n].info.static]
            if static:
                raise InvalidArgumentError(f"entity {static[0]!r} is static: it has no mass")
        self.structure = object()
        self.engine.update(names, props)
        changes = {field: getattr(props, field) for field in
                   ("mass", "friction", "restitution", "tags")
                   if getattr(props, field) is not None}
        for name in names:  # a new info, never an edit: a fork shares its source's
            entity = self.entities[name]
            entity.info = dataclasses.replace(entity.info, **changes)

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray,
                          where: str = "set_joint_damping") -> None:
        """These 1-DOF joints' own damping (part of the structure, as a body's friction)."""
        self.joints.require_scalar(names, where)
        self.structure = object()
        self.joints.set_damping(names, np.asarray(damping, float), where)

    def set_params(self, params: dict[str, Any]) -> None:
        """The engine's parameters (part of the structure)."""
        self.structure = object()
        self.engine.set_params(params)

    def require_valid(self) -> None:
        """Refuse to serve a faulted world, saying how it diverged (whoever noticed first:
        a request, or the telemetry's check between requests)."""
        if self.faulted:
            raise PhysicsError(
                f"{self.fault_cause or 'the simulation diverged'}; reset it (scope 'state' "
                "or 'all') before reading states")

    # -- time ---------------------------------------------------------------------------
    @property
    def sim_time(self) -> float:
        """Steps times timestep since the timestep last changed: no drift from summing."""
        base_step, base_time, dt = self._time_base
        return base_time + (self.step_index - base_step) * dt

    def _rebase_clock(self, sim_time: float | None = None) -> None:
        now = self.sim_time if sim_time is None else sim_time
        self._time_base = (self.step_index, now, self.engine.timestep)

    def step(self, count: int) -> None:
        """Advance ``count`` steps, unchecked: ``verify`` before anything reads the state."""
        self.require_valid()
        if self.engine.timestep != self._time_base[2]:
            self._rebase_clock()
        while count > 0:  # in chunks that end where a held wrench ends
            until_end = self.wrenches.steps_to_next_end(self.step_index)
            chunk = count if until_end is None else max(1, min(count, until_end))
            self.engine.step(chunk)
            self.step_index += chunk
            count -= chunk
            self.wrenches.expire(self.engine, self.step_index)

    def verify(self) -> None:
        """Check the steps taken since the last check; a non-finite state faults the world.

        Checking reads every body on some engines, so it runs once per batch of steps and
        before any state leaves the daemon, never per step.
        """
        self.require_valid()
        if self.verified_step == self.step_index and not self.teleported:
            return
        if not self.engine.state_within(self.limits.max_position, self.limits.max_speed):
            self.faulted = True
            when = (f"within steps {self.verified_step + 1}..{self.step_index}"
                    if self.verified_step < self.step_index else "by the states a request set")
            self.fault_cause = (
                f"the simulation diverged (NaN, infinite, or beyond "
                f"{self.limits.max_position:g} m or {self.limits.max_speed:g} m/s) {when}")
            raise PhysicsError(f"{self.fault_cause}; the world is paused and its states will "
                               "not be served until a reset")
        self.verified_step = self.step_index
        self.teleported = False

    def reset(self, scope: str) -> None:
        check_scope(scope)
        self.surprise.clear()  # what surprised the world before is no streak of the next
        with contextlib.suppress(PhysicsError):
            self.verify()  # a divergence in unchecked steps must not be forgotten
        if scope in ("time", "all"):
            self.wrenches.rewind(self.step_index)
            self.step_index = 0
            self.verified_step = 0
            self._rebase_clock(0.0)
        if scope in ("spawned", "all"):
            self.layout += 1
            self.structure = object()
            self.engine.clear()
            self.entities.clear()
            self.joints.refresh()
            self.wrenches.ends.clear()
            self.faulted = False
            self.verified_step = self.step_index
            self.teleported = False
        if scope == "state":
            self.restore_initial_states()

    def restore_initial_states(self) -> None:
        """Every entity to its created state: bodies and model roots by their poses and
        twists, models' joints to their as-loaded positions, targets and wrenches off."""
        names = [n for n, e in self.entities.items() if e.info.shape != "link"]
        if names:
            poses = np.stack([self.entities[n].initial_pose for n in names])
            twists = np.stack([self.entities[n].initial_twist for n in names])
            self.engine.set_states(names, poses, twists)
        self.engine.restore_joints()
        self.joints.release_all()
        self.wrenches.ends.clear()
        self.engine.reset_dynamics()
        self.faulted = False
        self.verified_step = self.step_index
        self.teleported = False


def check_scope(value: Any) -> str:
    """A reset scope, checked before anything is cancelled or reset."""
    scope = check_type(value, str, "reset.scope")
    if scope not in RESET_SCOPES:
        raise InvalidArgumentError(
            f"reset.scope {brief(scope)} is not one of {', '.join(RESET_SCOPES)}"
            f"{did_you_mean(scope[:64], RESET_SCOPES)}")
    return scope


def check_state_values(limits: Limits, poses: np.ndarray | None, twists: np.ndarray | None,
                       where: str) -> None:
    """Refuse, up front, a pose beyond ``max_position`` or a twist component beyond
    ``max_speed``: a world set there would read as diverged."""
    for values, limit, what, unit in ((poses, limits.max_position, "position", "m"),
                                      (twists, limits.max_speed, "speed", "m/s or rad/s")):
        if values is None:
            continue
        part = values[:, :3] if what == "position" else values
        beyond = np.abs(part) > limit
        if beyond.any():
            row, col = np.argwhere(beyond)[0].tolist()
            raise InvalidArgumentError(
                f"{where}: {float(part[row, col]):g} (row {row}) is beyond the world's "
                f"{what} limit of {limit:g} {unit}: it would read as diverged",
                {"limit": f"max_{what}", "max": limit})


def canonical_quaternions(poses: np.ndarray) -> np.ndarray:
    """q and -q are one rotation: serve the one with qw >= 0 (and, when qw is 0, the first
    non-zero of qx, qy, qz positive), so both engines give the same numbers."""
    quats = poses[:, 3:7]
    flip = quats[:, 3] < 0
    zero_w = quats[:, 3] == 0
    if zero_w.any():
        first = np.argmax(quats[:, :3] != 0, axis=1)
        flip |= zero_w & (quats[np.arange(len(quats)), first] < 0)
    if flip.any():
        poses = poses.copy()
        poses[flip, 3:7] *= -1.0
    return poses


def _number_or_none(value: float) -> float | None:
    return None if math.isnan(value) else value


def _require_massive(group: BodyGroup) -> None:
    """A moving body with no given mass weighs DENSITY times its volume: one under MIN_MASS
    is refused here, as a snapshot holding it is refused on restore (one rule for both;
    lighter bodies overflow a push in every engine)."""
    if group.static or group.mass is not None:
        return
    mass = default_mass(group)
    if not mass >= MIN_MASS:
        raise InvalidArgumentError(
            f"spawn: a moving {group.shape} of size {list(group.size)} weighs {mass:.3g} kg at "
            f"{DENSITY:g} kg/m³, under the lightest body MIN_MASS {MIN_MASS:g} kg: give "
            "it a mass or a larger size", details={"field": "mass", "min": MIN_MASS})
