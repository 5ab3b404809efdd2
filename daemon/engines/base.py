"""The one interface every physics engine implements; engine-specific code stays in engines/.

The daemon's ``World`` validates every request (names, shapes, finite numbers) and keeps the
entity registry, the clock and the step counter, so an engine receives only checked data,
addressed by entity name, and never sees the wire. Engines are driven from one thread.

An engine raises ``galton.protocol`` errors: ``FeatureUnsupportedError`` for what it
cannot do (and leaves it out of ``capabilities().features``), ``InvalidArgumentError`` for
a bad parameter value, ``OperationFailedError`` when the engine itself fails. A failed call
leaves the engine's scene as it was before the call.
"""

from __future__ import annotations

import contextlib
import os
import sys
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, NamedTuple

import numpy as np

from galton.daemon.engines.params import ParamSpec
from galton.protocol import (
    BODY_SHAPES,
    PROTOCOL_VERSION,
    BodyGroup,
    BodyProperties,
    Capabilities,
    EntityInfo,
    FeatureUnsupportedError,
    JointInfo,
)

# Feature flags an engine may list in its capabilities.
FEATURE_SPAWN = "spawn"
FEATURE_DELETE = "delete"
FEATURE_SET_STATE = "set_state"
FEATURE_UPDATE_MASS = "update_mass"
FEATURE_UPDATE_FRICTION = "update_friction"
FEATURE_UPDATE_RESTITUTION = "update_restitution"
FEATURE_UPDATE_RGBA = "update_rgba"
FEATURE_LOAD_MODEL = "load_model"
FEATURE_STATIC_POSE = "set_static_pose"
FEATURE_JOINTS = "joints"  # joints, get_joint_states, set_joint_states
FEATURE_JOINT_TARGETS = "joint_targets"
FEATURE_TARGET_POSITION = "target_position"
FEATURE_TARGET_VELOCITY = "target_velocity"
FEATURE_TARGET_EFFORT = "target_effort"
FEATURE_WRENCH = "wrench"
FEATURE_SNAPSHOT = "snapshot"
FEATURE_RENDER = "render"
FEATURE_RAYCAST = "raycast"
FEATURE_CONTACTS = "contacts"
FEATURE_MODEL_SHAPES = "model_shapes"  # get_shapes answers for a loaded model's bodies
FEATURE_SPAWN_INERTIA = "spawn_inertia"  # spawn groups' own ``inertia``
IMAGE_OUTPUTS = ("rgb", "depth", "segmentation")
# Every feature flag the protocol knows: an engine lists those it has, and no other.
KNOWN_FEATURES = (FEATURE_SPAWN, FEATURE_DELETE, FEATURE_SET_STATE, FEATURE_UPDATE_MASS,
                  FEATURE_UPDATE_FRICTION, FEATURE_UPDATE_RESTITUTION, FEATURE_UPDATE_RGBA,
                  FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE, FEATURE_JOINTS,
                  FEATURE_JOINT_TARGETS, FEATURE_TARGET_POSITION, FEATURE_TARGET_VELOCITY,
                  FEATURE_TARGET_EFFORT, FEATURE_WRENCH, FEATURE_SNAPSHOT, FEATURE_RENDER,
                  FEATURE_RAYCAST, FEATURE_CONTACTS, FEATURE_SPAWN_INERTIA,
                  FEATURE_MODEL_SHAPES)
# What every engine does: the abstract methods below (spawn, delete, set_states, update,
# load_model).
CORE_FEATURES = (FEATURE_SPAWN, FEATURE_DELETE, FEATURE_SET_STATE, FEATURE_UPDATE_MASS,
                 FEATURE_UPDATE_FRICTION, FEATURE_UPDATE_RESTITUTION, FEATURE_UPDATE_RGBA,
                 FEATURE_LOAD_MODEL, FEATURE_STATIC_POSE)
# The optional features, each with the method an engine overrides to have it.
FEATURE_METHODS = {FEATURE_JOINTS: "get_joint_states", FEATURE_JOINT_TARGETS: "set_joint_targets",
                   FEATURE_WRENCH: "set_wrenches", FEATURE_SNAPSHOT: "snapshot",
                   FEATURE_RENDER: "render", FEATURE_RAYCAST: "raycast",
                   FEATURE_CONTACTS: "contacts", FEATURE_MODEL_SHAPES: "shapes"}
TARGET_MODE_FEATURES = {"position": FEATURE_TARGET_POSITION,
                        "velocity": FEATURE_TARGET_VELOCITY, "effort": FEATURE_TARGET_EFFORT}
# One collision shape: kind (a BODY_SHAPES name or "mesh"), half sizes as SIZE_LAYOUT
# (a mesh: the half sizes of a box around it), its pose in its body's frame (7 wide).
Shape = tuple[str, tuple[float, ...], tuple[float, ...]]
# A mesh shape's triangles: (n, 3) float64 vertices in its Shape's frame (its pose), (m, 3)
# vertex indices.
ShapeMesh = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class CameraView:
    """One camera of a render request, in the world frame, checked by the daemon: it looks
    from ``eye`` at ``target`` with ``up`` up (unit, not along the view)."""

    eye: np.ndarray  # (3,)
    target: np.ndarray  # (3,)
    up: np.ndarray  # (3,)
    fov_deg: float  # vertical field of view
    width: int
    height: int
    near: float
    far: float
    outputs: tuple[str, ...]  # among IMAGE_OUTPUTS


@dataclass(frozen=True)
class Target:
    """A target held on one joint (``set_joint_targets``; mode "none" is never held: it is
    the absence of one)."""

    mode: str
    target: float
    kp: float
    kd: float
    max_effort: float


class RayHits(NamedTuple):
    """What ``Engine.raycast`` finds, per ray (a plain 5-tuple before; it unpacks the same)."""

    hit: np.ndarray  # (n,) bool
    entity: list[str]  # "" for a miss
    point: np.ndarray  # (n, 3), NaN for a miss
    normal: np.ndarray  # (n, 3), NaN for a miss
    distance: np.ndarray  # (n,), NaN for a miss


class ContactPoints(NamedTuple):
    """What ``Engine.contacts`` reports, per contact point (a plain 6-tuple before)."""

    first: list[str]
    second: list[str]
    position: np.ndarray  # (n, 3)
    normal: np.ndarray  # (n, 3), from the first entity to the second
    force: np.ndarray  # (n,) N, normal force
    penetration: np.ndarray  # (n,) m


class Engine(ABC):
    """A physics world holding named rigid bodies, stepped with a fixed timestep."""

    name: ClassVar[str]
    # Whether ``step`` lets other Python threads run while it computes. An engine that holds
    # the GIL needs a short switch interval so that status requests (answered on Zenoh's
    # threads) get in between its steps; one that releases it runs faster without.
    releases_gil_while_stepping: ClassVar[bool] = False
    # What capabilities() tells, declared by each engine (its params.py and models.py).
    param_specs: ClassVar[Mapping[str, ParamSpec]]
    model_formats: ClassVar[tuple[str, ...]]
    body_shapes: ClassVar[tuple[str, ...]] = tuple(BODY_SHAPES)
    # The joint target modes set_joint_targets holds (where the engine overrides it).
    target_modes: ClassVar[tuple[str, ...]] = tuple(TARGET_MODE_FEATURES)
    # Whether spawn honours a group's own ``inertia`` (FEATURE_SPAWN_INERTIA).
    spawn_inertia: ClassVar[bool] = False

    @classmethod
    def features(cls) -> tuple[str, ...]:
        """What this engine does, derived once here from what it implements: the core every
        engine has, each optional method it overrides, the target modes and spawn inertia
        it declares; in KNOWN_FEATURES order."""
        have = set(CORE_FEATURES)
        have.update(feature for feature, method in FEATURE_METHODS.items()
                    if getattr(cls, method) is not getattr(Engine, method))
        if FEATURE_JOINT_TARGETS in have:
            have.update(TARGET_MODE_FEATURES[mode] for mode in cls.target_modes)
        if cls.spawn_inertia:
            have.add(FEATURE_SPAWN_INERTIA)
        return tuple(f for f in KNOWN_FEATURES if f in have)

    @classmethod
    @abstractmethod
    def engine_version(cls) -> str:
        """The version of the simulator this engine drives."""

    def render_backend(self) -> str | None:
        """How the engine renders headless (egl, osmesa, tinyrenderer); None: no render."""
        return None

    def capabilities(self) -> Capabilities:
        """Engine name and version, body shapes, model formats, features, parameters: all
        from the engine's declarations (``features`` from what it overrides)."""
        return Capabilities(
            engine=self.name, engine_version=self.engine_version(),
            protocol_version=PROTOCOL_VERSION, body_shapes=self.body_shapes,
            model_formats=self.model_formats, features=self.features(),
            params={name: spec.describe() for name, spec in self.param_specs.items()},
            render_backend=self.render_backend())

    @abstractmethod
    def spawn(self, groups: Sequence[BodyGroup]) -> None:
        """Add every body of every group in one batch (names are new and unique).

        A body's initial twist is ``group.twists`` (zeros when None). ``mass`` None means a
        density of 1000 kg/m³; ``friction``/``restitution`` None mean the engine defaults.
        The running world keeps its state (positions, velocities) across the call.
        """

    @abstractmethod
    def load_model(self, fmt: str, text: str | None, path: str | None,
                   prefix: str, *, fixed_base: bool = True) -> list[EntityInfo]:
        """Load a model (format from capabilities().model_formats) given as text or path.

        The daemon hands over text whose file references (meshes, textures) are already
        absolute (daemon/world/model_files.py), so an engine never resolves files itself.

        Every top-level body is a model: its root becomes an entity named ``prefix + body
        name`` with ``shape="model"``, and every other body (link) of its subtree an entity
        ``prefix + link name`` with ``shape="link"``; all have ``source="model"`` and
        ``model`` set to the root's name. Return them, each root before its links.
        ``fixed_base`` (URDF only) welds a URDF's root to the world; False gives it a free
        joint. Raise InvalidArgumentError for a model that does not parse, and
        NameNotUniqueError (or InvalidArgumentError) when a name is taken; in both cases
        leave the world unchanged.
        """

    @abstractmethod
    def delete(self, names: Sequence[str]) -> None:
        """Remove these bodies in one batch and free what they held."""

    @abstractmethod
    def get_states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """Poses (n, 7: x y z qx qy qz qw) and world twists (n, 6: v, ω) of these bodies."""

    def pose_reader(self, names: Sequence[str]) -> Callable[[], np.ndarray]:
        """A function that reads these bodies' poses (n, 7), for a state stream that reads
        the same names 60 times a second: an engine may work out once where they live. Valid
        until the next spawn, load_model, delete or clear; by default, get_states."""
        fixed = list(names)
        return lambda: self.get_states(fixed)[0]

    @abstractmethod
    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        """Teleport bodies and/or set their velocities (None leaves that part as it is)."""

    @abstractmethod
    def update(self, names: Sequence[str], props: BodyProperties) -> None:
        """Change mass, friction, restitution or colour (tags are the World's business)."""

    @abstractmethod
    def step(self, count: int) -> None:
        """Advance the physics by ``count`` fixed timesteps."""

    @abstractmethod
    def state_within(self, max_position: float, max_speed: float) -> bool:
        """False when the world has diverged: any moving body's position or velocity is NaN
        or infinite, any coordinate of its position is beyond ``max_position`` metres from
        the origin, any component of its linear or angular velocity beyond ``max_speed``
        (m/s, rad/s), or the engine detected a divergence in any ``step`` since the last
        ``reset_dynamics``/``clear``. Absurd finite states count: a ball at x = 4e299 has
        diverged as surely as one at NaN.

        The World calls it once per batch of steps, not after every step."""

    @abstractmethod
    def properties(self, names: Sequence[str]) -> np.ndarray:
        """The effective (n, 3) mass (kg), friction and restitution of these entities: what
        the engine simulates, defaults included, never None. A static body's mass is NaN
        (it has none); a loaded model's mass is its whole subtree's."""

    @abstractmethod
    def clear(self) -> None:
        """Remove every body: an empty world (parameters kept)."""

    @abstractmethod
    def reset_dynamics(self) -> None:
        """Forget contact caches and warm starts after a teleport of every body."""

    @property
    @abstractmethod
    def timestep(self) -> float:
        """Seconds of simulated time per step."""

    @abstractmethod
    def get_params(self) -> dict[str, Any]:
        """Every parameter in capabilities().params with its current value."""

    @abstractmethod
    def set_params(self, params: dict[str, Any]) -> None:
        """Set parameters: all or none (validate every value before changing any).

        Unknown names raise InvalidArgumentError with a "did you mean"; names that belong to
        another engine raise FeatureUnsupportedError.
        """

    def close(self) -> None:  # noqa: B027 - optional hook, a no-op by default
        """Release the engine's resources."""

    # -- articulated models: joints, targets, wrenches (optional features) ---------------
    def joints(self) -> list[JointInfo]:
        """Every joint of every loaded model, in load order (docs/protocol.md, "joints")."""
        return []

    def get_joint_states(self, names: Sequence[str]
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and actuator efforts, (n,) each, of these 1-DOF joints.

        The effort is the generalized force the joint's target applied in the last step
        (0 with no target), passive damping and constraint forces excluded."""
        raise self._unsupported("joint states")

    def set_joint_states(self, names: Sequence[str], positions: np.ndarray,
                         velocities: np.ndarray | None) -> None:
        """Teleport these 1-DOF joints (velocities None: keep them) between steps."""
        raise self._unsupported("joint states")

    def set_joint_targets(self, names: Sequence[str], mode: str, targets: np.ndarray,
                          kp: np.ndarray, kd: np.ndarray, max_effort: np.ndarray) -> None:
        """Hold a target on these 1-DOF joints, applied every step by the engine itself.

        position: tau = kp (target - q) - kd qdot; velocity: tau = kd (target - qdot);
        effort: tau = target; none: tau = 0. tau is clipped to +-max_effort (inf: no clip).
        Arrays are (n,), checked and broadcast by the World."""
        raise self._unsupported("joint targets")

    def set_joint_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        """Set these 1-DOF joints' own viscous damping (N·m·s/rad or N·s/m, (n,), >= 0,
        checked by the World), beside any held target's kd: ``joints`` reports it and
        snapshots, restores and clones carry it (docs/PHYSICS.md, "Calibration")."""
        raise self._unsupported("joint damping")

    def set_wrenches(self, names: Sequence[str], wrenches: np.ndarray,
                     points: np.ndarray | None) -> None:
        """Hold a world-frame wrench (n, 6: force, torque) on each body until cleared.

        ``points`` (n, 3) are world-frame application points (None: each body's centre of
        mass c); the wrench is F at c plus tau + (p - c) x F, with c taken now, then held
        constant in the world frame. A new wrench on a body replaces its old one."""
        raise self._unsupported("wrenches")

    def clear_wrenches(self, names: Sequence[str] | None) -> None:  # noqa: B027 - none held
        """Remove the wrenches of these bodies (None: of every body)."""

    def restore_joints(self) -> None:  # noqa: B027 - nothing to restore without joints
        """Every joint back to its as-loaded position at rest, every target to none, every
        wrench cleared (reset "state" and stop, after the roots' poses are restored)."""

    # -- snapshots (docs/protocol.md, "snapshot") -------------------------------------------
    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        """The complete world (scene, parameters, dynamic state) as plain data msgpack can
        carry (never pickle: clients send snapshots back). Restoring it into a fresh engine
        and taking the same steps gives the same states bit for bit (each engine states
        exactly what it promises in its own docstring).

        ``canonical``: the restored world and this one go on identically, even where that
        means first making this world's hidden state (contact caches) canonical, which may
        change how it goes on (PyBullet rebuilds itself). False leaves this world untouched,
        and the restored world goes on as this one would after ``reset_dynamics``: what a
        fork, a prediction or a checkpoint wants."""
        raise self._unsupported("snapshots")

    def restore(self, data: dict[str, Any]) -> None:
        """Rebuild, on this FRESH engine, the world a snapshot describes. ``data`` is
        untrusted: InvalidArgumentError for anything malformed or from another engine or
        format (the daemon then discards this engine; the live world is untouched)."""
        raise self._unsupported("snapshots")

    def save_state(self) -> object | None:
        """The world's dynamic state, kept in memory, for a snapshot of an unchanged
        structure (the World tracks structure: ``World.save_state``): loading it into this
        engine, or a clone of it, while neither changed structure, goes on bit for bit as
        from now. None: no fast path (snapshots take the portable one)."""
        return None

    def load_state(self, state: object) -> bool:
        """Set a state ``save_state`` kept (of this world or of one it was cloned from or
        into, of the same structure); False, changing nothing, where it does not fit."""
        return False

    def recycle_state(self, state: object) -> None:  # noqa: B027 - nothing to reuse
        """A state ``save_state`` made that nobody holds any more: its memory may serve the
        next one (a slot replaced by a newer snapshot)."""

    # -- perception (docs/protocol.md, "render", "raycast", "contacts") ---------------------
    def render(self, cameras: Sequence[CameraView]
               ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
        """One dict of images per camera ("rgb" (h, w, 3) uint8, top row first; "depth"
        (h, w) float32 metres along the view axis, inf where nothing; "segmentation" (h, w)
        int32 indices into the returned entity names, -1 where nothing), as asked."""
        raise self._unsupported("rendering")

    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
                ) -> RayHits:
        """Per ray (unit directions, world frame): hit, entity ("" for none), point,
        normal, distance; NaN point, normal and distance for a miss."""
        raise self._unsupported("ray casts")

    def bounds(self, names: Sequence[str]) -> np.ndarray:
        """World-frame axis-aligned bounds (rows ``min xyz, max xyz``) of a loaded model's
        bodies, from their collision shapes; spawned primitives need no engine."""
        raise self._unsupported("bounds of loaded models")

    def shapes(self, names: Sequence[str]) -> list[list[Shape]]:
        """Each of a loaded model's bodies' collision shapes in its own frame (engines that
        answer list FEATURE_MODEL_SHAPES); spawned primitives need no engine."""
        raise self._unsupported("shapes of loaded models")

    def shape_meshes(self, names: Sequence[str]) -> list[dict[int, ShapeMesh]]:
        """The triangles of a loaded model's ``mesh`` shapes, by their index in each body's
        ``shapes`` list, where the engine keeps them; by default none (such a mesh is told
        as its box). Bodies that share a mesh may share its arrays."""
        return [{} for _ in names]

    def contacts(self, names: Sequence[str] | None
                 ) -> ContactPoints:
        """The last step's contact points (involving any of ``names``; None: all): the two
        entities, positions (n, 3), normals (n, 3) from the first to the second, normal
        forces (n,) N, penetrations (n,) m."""
        raise self._unsupported("contact queries")

    def entity_names(self) -> list[str] | None:
        """Every entity the engine holds (bodies, model roots, links), for the check of a
        restored world against its registry; None where the engine cannot say."""
        return None

    def clone(self) -> Engine:
        """A new engine holding a copy of this world, in this process, for a fork or a
        prediction: as ``restore(snapshot(canonical=False))`` into a fresh engine (this
        world untouched). Engines override it with a faster copy where they can."""
        fresh = type(self)()
        try:
            fresh.restore(self.snapshot(canonical=False))
        except Exception:
            fresh.close()
            raise
        return fresh

    def _unsupported(self, what: str) -> FeatureUnsupportedError:
        return FeatureUnsupportedError(f"the {self.name} engine does not support {what}")


@contextlib.contextmanager
def native_output_silenced() -> Iterator[None]:
    """Nothing a native library prints to the process's stdout or stderr while inside (a
    build banner, a debug line): the daemon's output is its own lines and its log. Python's
    own streams are flushed first, so nothing of ours is lost."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved:
            os.close(fd)
