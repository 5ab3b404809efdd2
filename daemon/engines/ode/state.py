"""Reading and writing states: ODE's own memory, read as one numpy stack per call.

Each moving body's position, rotation, quaternion and velocities lie in 28 doubles inside
ODE (native.check_layout); the engine keeps a numpy view of them per body, so reading n
bodies is one ``np.stack`` and two column picks, with no ctypes call per body.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from galton.daemon.engines.ode.native import AVEL, LIB, LVEL, POS, QUAT, quaternion
from galton.daemon.engines.ode.spawn import AWAKE, Body, place_static

POSE_COLUMNS = [POS, POS + 1, POS + 2, QUAT + 1, QUAT + 2, QUAT + 3, QUAT]  # x y z, x y z w
TWIST_COLUMNS = [LVEL, LVEL + 1, LVEL + 2, AVEL, AVEL + 1, AVEL + 2]
# Values past these are not handed to ODE (its hash space and solver would be at risk): the
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
    return poses, twists


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
            pose = poses[k].tolist()
            LIB.dBodySetPosition(handle, *pose[:3])
            LIB.dBodySetQuaternion(handle, quaternion(pose[3:]))
        if twists is not None:
            twist = twists[k].tolist()
            LIB.dBodySetLinearVel(handle, *twist[:3])
            LIB.dBodySetAngularVel(handle, *twist[3:])
        wake(body)


def wake(body: Body) -> None:
    """Enable the body with fresh idle counters (dBodyEnable restarts them)."""
    LIB.dBodyEnable(body.body)
    if not body.awake:
        body.awake = True
        body.set_bits(AWAKE)


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
