"""The protocol's words and sizes (shapes, states, modes, engines, widths) and its one rule
for keys: plain Python, no numpy, so that a command line lists its choices in a blink."""

from __future__ import annotations

from collections.abc import Sequence
from enum import StrEnum
from typing import Any, Literal, get_args

from galton.protocol.errors import InvalidArgumentError, brief, did_you_mean

POSE_WIDTH = 7
TWIST_WIDTH = 6
MAX_BATCH = 100_000
MAX_NAME_LENGTH = 128
MAX_MASS = 1e9  # kg: a body's mass (spawn, update, snapshot edits), and its principal moments
MAX_FRICTION = 100.0  # a body's friction coefficient
MAX_WORLD_NAME = 64  # a world's or a snapshot slot's name
MAX_CAMERA_NAME = 64
# The bounds of every number a client sends that reaches an engine (docs/protocol.md,
# "Bounds"), the same on every engine and front: each is finite and well inside what every
# engine integrates without overflowing (ODE aborts the process on a quaternion that a
# product of two such numbers turns infinite). The daemon's own max_position / max_speed
# limits (tighter by default) still apply to poses and twists on top of these.
QUATERNION_NORM_BAND = (0.5, 2.0)  # a pose's quaternion norm: normalised within, refused out
MAX_COORDINATE = 1e9  # m: a position in a pose, an apply_wrench point, a ray's origin or end
MAX_TWIST = 1e7  # m/s or rad/s: each component of a twist
MAX_FORCE = 1e9  # N: apply_wrench's force components
MAX_TORQUE = 1e9  # N m: apply_wrench's torque components
MAX_EFFORT = 1e9  # N or N m: effort targets and max_effort (which may also be +inf: no cap)
MAX_JOINT_POSITION = 1e6  # rad or m: joint positions and position targets
MAX_JOINT_SPEED = 1e7  # rad/s or m/s: joint velocities and velocity targets
MAX_GAIN = 1e9  # kp (N/m or N m/rad) and kd (N s/m or N m s/rad)
MIN_MASS = 1e-6  # kg: the lightest body (spawn, update); lighter ones overflow a push
MIN_INERTIA = 1e-12  # kg m²: the smallest principal moment a spawn's inertia may set
# Ranges and defaults of request fields that are the protocol's, not a daemon's option
# (protocol/requests.py declares them; the daemon's own limits stay in its Limits).
MAX_RTF = 1e6  # play / set_rtf
MIN_RATE_HZ, MAX_RATE_HZ, DEFAULT_RATE_HZ = 1.0, 60.0, 10.0  # stream_states
MAX_CAMERAS_PER_REQUEST = 16  # render
DEFAULT_MAX_LENGTH = 100.0  # m, raycast: a ray's reach when none is given
# compare's default sigmas: how far off a pose may be before its score grows past 1.
DEFAULT_SIGMA_POSITION, DEFAULT_SIGMA_ANGLE, DEFAULT_SIGMA_SPEED = 0.01, 0.05, 0.1  # m, rad, m/s


class SimState(StrEnum):
    """Where a world's clock is; a str on the wire ("stopped", "playing", "paused")."""

    STOPPED = "stopped"  # at time 0 with every entity in its created state
    PLAYING = "playing"  # advancing on its own at the target real-time factor
    PAUSED = "paused"  # holding its time; steps only on request


SIM_STATES = tuple(state.value for state in SimState)
# Each choice list is spelled once, as a Literal type: requests are declared with it
# (protocol/requests.py) and the tuples below are read from it.
ResetScope = Literal["time", "state", "spawned", "all"]
RESET_SCOPES: tuple[str, ...] = get_args(ResetScope)
EntityKind = Literal["static", "dynamic"]
ENTITY_KINDS: tuple[str, ...] = get_args(EntityKind)
ModelFormat = Literal["mjcf", "urdf"]
MODEL_FORMATS: tuple[str, ...] = get_args(ModelFormat)
ImageFormat = Literal["raw", "png"]
IMAGE_FORMATS: tuple[str, ...] = get_args(ImageFormat)
BODY_SHAPES = ("sphere", "box", "cylinder", "capsule", "plane", "mesh")
# What list reports for the bodies of a loaded model: its root, and every other link.
MODEL_SHAPES = ("model", "link")
JOINT_TYPES = ("revolute", "prismatic", "spherical", "free", "fixed")
SCALAR_JOINT_TYPES = ("revolute", "prismatic")  # one degree of freedom: states and targets
TargetMode = Literal["none", "position", "velocity", "effort"]
TARGET_MODES: tuple[str, ...] = get_args(TargetMode)
# The engines a daemon may host (``load_world``'s and ``create_world``'s choices).
EngineName = Literal["mujoco", "pybullet", "ode", "dart"]
ENGINE_NAMES: tuple[str, ...] = get_args(EngineName)
WRENCH_WIDTH = 6  # fx fy fz tx ty tz, world frame
# How many numbers ``size`` holds per shape, and what they mean (all half sizes, metres).
SIZE_LAYOUT: dict[str, tuple[str, ...]] = {
    "sphere": ("radius",),
    "box": ("half_x", "half_y", "half_z"),
    "cylinder": ("radius", "half_length"),
    "capsule": ("radius", "half_length"),
    "plane": ("half_x", "half_y"),
    # A mesh's size is not sent: it is its vertices' reach from the body's origin.
    "mesh": ("half_x", "half_y", "half_z"),
}
# A mesh's bounds (protocol/mesh.py): a board's part needs tens; these leave room for a
# scanned object while keeping one group's decode and an engine's hull build in milliseconds.
MAX_MESH_VERTICES = 20_000
MAX_MESH_FACES = 40_000


def check_fields(body: dict[str, Any], allowed: Sequence[str], where: str) -> None:
    """The one rule for keys: a field that is not one of ``allowed`` is refused, naming the
    closest one (operations' arguments, spawn groups, update properties, until_rest)."""
    for key in body:
        if key not in allowed:
            raise InvalidArgumentError(
                f"{where} takes no field {brief(key)}{did_you_mean(str(key)[:64], allowed)}; "
                f"it takes: {', '.join(allowed)}")
