"""Rigid transforms as (position (3,), quaternion x y z w (4,)) pairs, for links whose ODE
body sits at their centre of mass rather than at their URDF frame."""

from __future__ import annotations

import numpy as np

Frame = tuple[np.ndarray, np.ndarray]
IDENTITY: Frame = (np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0]))


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The quaternion a·b (x y z w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])


def conjugate(q: np.ndarray) -> np.ndarray:
    return np.array([-q[0], -q[1], -q[2], q[3]])


def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """v turned by the unit quaternion q."""
    u, w = q[:3], q[3]
    return np.asarray(v + 2.0 * np.cross(u, np.cross(u, v) + w * v))


def compose(a: Frame, b: Frame) -> Frame:
    """a then b: b expressed in a's frame, brought to a's parent."""
    return a[0] + rotate(a[1], b[0]), multiply(a[1], b[1])


def inverse(a: Frame) -> Frame:
    q = conjugate(a[1])
    return -rotate(q, a[0]), q


def from_matrix(matrix: np.ndarray) -> Frame:
    """A 4x4 homogeneous transform as a frame."""
    r = matrix[:3, :3]
    trace = float(np.trace(r))
    if trace > 0:
        s = 2.0 * np.sqrt(trace + 1.0)
        q = [(r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s,
             0.25 * s]
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + r[i, i] - r[j, j] - r[k, k])
        q = [0.0, 0.0, 0.0, (r[k, j] - r[j, k]) / s]
        q[i], q[j], q[k] = 0.25 * s, (r[j, i] + r[i, j]) / s, (r[k, i] + r[i, k]) / s
    quat = np.array(q, dtype=float)
    return np.asarray(matrix[:3, 3], dtype=float), quat / np.linalg.norm(quat)


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    return np.array([*(np.sin(angle / 2) * axis), np.cos(angle / 2)])
