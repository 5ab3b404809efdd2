"""Reading and writing states: ODE's own memory, read as one numpy stack per call.

Each moving body's position, rotation, quaternion and velocities lie in 28 doubles inside
ODE (native.check_layout); the engine keeps a numpy view of them per body, so reading n
bodies is one ``np.stack`` and two column picks, with no ctypes call per body.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Sequence

import numpy as np

from galton.daemon.engines.ode import frames
from galton.daemon.engines.ode.native import (
    AVEL,
    LIB,
    LVEL,
    POS,
    QUAT,
    REAL,
    STATE_LENGTH,
    quaternion,
)
from galton.daemon.engines.ode.spawn import AWAKE, Body, place_static

POSE_COLUMNS = [POS, POS + 1, POS + 2, QUAT + 1, QUAT + 2, QUAT + 3, QUAT]  # x y z, x y z w
TWIST_COLUMNS = [LVEL, LVEL + 1, LVEL + 2, AVEL, AVEL + 1, AVEL + 2]
# Values past these are not handed to ODE (its space and solver would be at risk): the
# world is marked diverged instead, as the interface wants of such a state.
WILD = 1e15


def read(bodies: Sequence[Body]) -> tuple[np.ndarray, np.ndarray]:
    """Poses (n, 7) and twists (n, 6) of these bodies, static ones as placed, at rest."""
    count = len(bodies)
    poses, twists = np.zeros((count, 7)), np.zeros((count, 6))
    moving = [k for k, b in enumerate(bodies) if not b.static]
    if moving:
        stacked = np.stack([bodies[k].state for k in moving])
        poses[moving] = stacked[:, POSE_COLUMNS]
        twists[moving] = stacked[:, TWIST_COLUMNS]
    for k, body in enumerate(bodies):
        if body.static:
            poses[k] = body.pose
        elif body.frame is not None:
            poses[k], twists[k] = link_state(body, poses[k], twists[k])
    return poses, twists


class PoseReader:
    """A state stream's reader of fixed bodies: one numpy gather over ODE's memory.

    A moving body's 28 doubles lie at a fixed address for the body's life, so the poses of
    n bodies are one fancy index into a view that spans their addresses (a stream's whole
    sample of 1,000 poses: 99 µs, against 1.4 ms with a stack of n views; PERFORMANCE.md,
    "State streams and the view"). Only those addresses are ever read,
    so the gaps between them (other allocations, or none mapped) are never touched. Static
    bodies and links whose frame is not their centre of mass read as ``read`` reads them.
    The engine makes a new reader when its bodies change (``OdeEngine.generation``).
    """

    def __init__(self, bodies: Sequence[Body]) -> None:
        self.bodies = list(bodies)
        plain = [not b.static and b.frame is None for b in self.bodies]
        self.plain = np.flatnonzero(plain)
        self.rest = [k for k, gathered in enumerate(plain) if not gathered]
        self.memory = np.zeros(0)
        self.index = np.zeros((0, len(POSE_COLUMNS)), dtype=np.intp)
        if len(self.plain):
            self._map([self.bodies[k] for k in self.plain])

    def _map(self, bodies: Sequence[Body]) -> None:
        size = ctypes.sizeof(REAL)
        addresses = np.array([b.state.ctypes.data for b in bodies], dtype=np.intp)
        base = int(addresses.min())
        span = int(addresses.max() - base) // size + STATE_LENGTH
        pointer = ctypes.cast(base, ctypes.POINTER(REAL))
        self.memory = np.ctypeslib.as_array(pointer, shape=(span,))
        self.index = ((addresses - base) // size)[:, None] + np.array(POSE_COLUMNS)

    def __call__(self) -> np.ndarray:
        poses = np.empty((len(self.bodies), 7))
        poses[self.plain] = self.memory[self.index]
        if self.rest:
            poses[self.rest] = read([self.bodies[k] for k in self.rest])[0]
        return poses


def link_state(body: Body, pose: np.ndarray, twist: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """A link's frame and its twist there, from its body at the centre of mass."""
    assert body.frame is not None
    position, turn = frames.compose((pose[:3], pose[3:]), frames.inverse(body.frame))
    linear = twist[:3] + np.cross(twist[3:], position - pose[:3])
    return np.concatenate([position, turn]), np.concatenate([linear, twist[3:]])


def body_pose(body: Body, pose: np.ndarray) -> np.ndarray:
    """Where the body (at the centre of mass) is when its link's frame is at ``pose``."""
    if body.frame is None:
        return pose
    position, turn = frames.compose((pose[:3], pose[3:]), body.frame)
    return np.concatenate([position, turn])


def wild(values: np.ndarray | None) -> bool:
    return values is not None and not bool(np.all(np.abs(values) < WILD))


def write(bodies: Sequence[Body], poses: np.ndarray | None, twists: np.ndarray | None
          ) -> None:
    """Teleport and/or set velocities; a moving body so touched wakes up."""
    for k, body in enumerate(bodies):
        if body.static:
            if poses is not None:
                place_static(body, poses[k].tolist())
            continue
        handle = body.body
        if poses is not None:
            pose = body_pose(body, poses[k]).tolist()
            LIB.dBodySetPosition(handle, *pose[:3])
            LIB.dBodySetQuaternion(handle, quaternion(pose[3:]))
        if twists is not None:
            twist = body_twist(body, twists[k]).tolist()
            LIB.dBodySetLinearVel(handle, *twist[:3])
            LIB.dBodySetAngularVel(handle, *twist[3:])
        wake(body)


def body_twist(body: Body, twist: np.ndarray) -> np.ndarray:
    """The body's twist at its centre of mass from its link's twist at the link's frame."""
    if body.frame is None:
        return twist
    pose = read([body])[0][0]  # the link's frame now (poses are set before twists)
    centre = body.state[POS:POS + 3]
    return np.concatenate([twist[:3] + np.cross(twist[3:], centre - pose[:3]), twist[3:]])


def wake(body: Body) -> None:
    """Enable the body with fresh idle counters (dBodyEnable restarts them)."""
    LIB.dBodyEnable(body.body)
    if not body.awake:
        body.awake = True
        body.set_bits(AWAKE)


def tame(bodies: Sequence[Body]) -> bool:
    """No NaN, infinity or absurd value in these bodies' states: checked after every step,
    since ODE's solver may loop forever on a NaN (one stack and one sum)."""
    total = float(np.abs(np.stack([b.state for b in bodies])).sum())  # NaN, inf or huge
    return total < WILD


def within(bodies: Sequence[Body], max_position: float, max_speed: float) -> bool:
    moving = [b.state for b in bodies if not b.static]
    if not moving:
        return True
    stacked = np.stack(moving)
    position = stacked[:, POS:POS + 3]
    speeds = stacked[:, TWIST_COLUMNS]
    if not (np.isfinite(position).all() and np.isfinite(speeds).all()):
        return False
    return bool(np.abs(position).max() <= max_position
                and np.abs(speeds).max() <= max_speed and math.isfinite(max_speed))
