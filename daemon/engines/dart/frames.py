"""Poses and twists between the protocol's form and DART's free joint.

A free joint's six positions are the rotation vector (log map) of its child's orientation,
then its position in the world; its six velocities are the child's angular and linear
velocity in the world frame (dartpy 6.20; tests/daemon/engines/test_dart_engine.py checks it).
Converting them with numpy for a whole batch costs two DART calls per body (positions,
velocities) instead of one per quantity.
"""

from __future__ import annotations

import numpy as np

SMALL_ANGLE = 1e-8  # rad: below it sin(θ/2)/θ is taken from its series


def rotvecs_to_quats(rotvecs: np.ndarray) -> np.ndarray:
    """(n, 3) rotation vectors to (n, 4) quaternions x y z w."""
    theta = np.linalg.norm(rotvecs, axis=1)
    small = theta < SMALL_ANGLE
    safe = np.where(small, 1.0, theta)
    scale = np.where(small, 0.5 - theta ** 2 / 48.0, np.sin(safe / 2.0) / safe)
    return np.column_stack([rotvecs * scale[:, None], np.cos(theta / 2.0)])


def quats_to_rotvecs(quats: np.ndarray) -> np.ndarray:
    """(n, 4) quaternions x y z w (not necessarily unit) to (n, 3) rotation vectors."""
    q = quats / np.linalg.norm(quats, axis=1)[:, None]
    q = np.where(q[:, 3:4] < 0, -q, q)  # the shorter way round
    sin_half = np.linalg.norm(q[:, :3], axis=1)
    theta = 2.0 * np.arctan2(sin_half, q[:, 3])
    small = sin_half < SMALL_ANGLE
    scale = np.where(small, 2.0, theta / np.where(small, 1.0, sin_half))
    rotvecs: np.ndarray = q[:, :3] * scale[:, None]
    return rotvecs


def rotations(rotvecs: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of rotation vectors (Rodrigues)."""
    theta = np.linalg.norm(rotvecs, axis=1)
    small = theta < SMALL_ANGLE
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta ** 2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta ** 2 / 24.0, (1.0 - np.cos(safe)) / safe ** 2)
    x, y, z = rotvecs[:, 0], rotvecs[:, 1], rotvecs[:, 2]
    zero = np.zeros_like(x)
    k = np.stack([np.stack([zero, -z, y], 1), np.stack([z, zero, -x], 1),
                  np.stack([-y, x, zero], 1)], 1)
    eye = np.broadcast_to(np.eye(3), k.shape)
    matrices: np.ndarray = eye + a[:, None, None] * k + b[:, None, None] * (k @ k)
    return matrices


def free_to_states(positions: np.ndarray, velocities: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(n, 6) free-joint positions and velocities to (n, 7) poses and (n, 6) world twists
    (linear first, as the protocol has them)."""
    poses = np.column_stack([positions[:, 3:], rotvecs_to_quats(positions[:, :3])])
    return poses, np.column_stack([velocities[:, 3:], velocities[:, :3]])


def poses_to_free(poses: np.ndarray) -> np.ndarray:
    """(n, 7) poses to (n, 6) free-joint positions."""
    return np.column_stack([quats_to_rotvecs(poses[:, 3:]), poses[:, :3]])


def twists_to_free(twists: np.ndarray) -> np.ndarray:
    """(n, 6) world twists to (n, 6) free-joint velocities."""
    return np.column_stack([twists[:, 3:], twists[:, :3]])


def matrix_to_quat(rot: np.ndarray) -> np.ndarray:
    """A 3×3 rotation matrix to a quaternion x y z w (Shepperd's method)."""
    trace = float(np.trace(rot))
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        return np.array([(rot[2, 1] - rot[1, 2]) / s, (rot[0, 2] - rot[2, 0]) / s,
                         (rot[1, 0] - rot[0, 1]) / s, 0.25 * s])
    i = int(np.argmax(np.diag(rot)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * np.sqrt(1.0 + rot[i, i] - rot[j, j] - rot[k, k])
    q = np.zeros(4)
    q[i] = 0.25 * s
    q[j] = (rot[j, i] + rot[i, j]) / s
    q[k] = (rot[k, i] + rot[i, k]) / s
    q[3] = (rot[k, j] - rot[j, k]) / s
    return q
