"""calibrate's observation as the request carries it (times, names, packed poses), checked
and turned into steps of the start world; and the start's twists where the request gives
none: estimated from the first samples (exact for a body under constant acceleration)."""

from __future__ import annotations

import numpy as np

from galton.daemon.core.candidates import Observation
from galton.protocol import POSE_WIDTH, InvalidArgumentError

MIN_SAMPLES = 2


def floats(raw: bytes, what: str) -> np.ndarray:
    if len(raw) % 8:
        raise InvalidArgumentError(f"calibrate.{what} must be packed float64, got "
                                   f"{len(raw)} bytes")
    return np.frombuffer(raw, dtype="<f8").astype(float)


def sample_times(raw: bytes) -> np.ndarray:
    """The sample times: at least two, finite, increasing."""
    times = floats(raw, "times")
    if len(times) < MIN_SAMPLES:
        raise InvalidArgumentError(f"calibrate.times needs at least {MIN_SAMPLES} samples "
                                   f"(the start and one seen after it), got {len(times)}")
    if not np.isfinite(times).all() or (np.diff(times) <= 0).any():
        raise InvalidArgumentError("calibrate.times must be finite and increasing")
    return times


def sample_poses(raw: bytes, samples: int, bodies: int) -> np.ndarray:
    """(samples, bodies, 7) poses; a row may be all NaN (not seen), never infinite."""
    values = floats(raw, "poses")
    if len(values) != samples * bodies * POSE_WIDTH:
        raise InvalidArgumentError(
            f"calibrate.poses holds {len(values) // POSE_WIDTH} rows of {POSE_WIDTH}; "
            f"{samples} samples of {bodies} bodies need {samples * bodies}")
    poses = values.reshape(samples, bodies, POSE_WIDTH)
    seen = ~np.isnan(poses).all(axis=2)
    if not np.isfinite(poses[seen]).all():
        raise InvalidArgumentError("calibrate.poses: a row must be finite, or all NaN (not "
                                   "seen)")
    if not seen[0].all():
        missing = int(np.flatnonzero(~seen[0])[0])
        raise InvalidArgumentError(f"calibrate.poses: body {missing} is not seen in the first "
                                   "sample, the start")
    return poses


def observation(names: list[str], times: np.ndarray, poses: np.ndarray, dt: float
                ) -> Observation:
    """The samples after the first, at whole steps of ``dt`` from it (rounded)."""
    steps = np.rint((times[1:] - times[0]) / dt).astype(np.int64)
    if (steps <= 0).any() or (np.diff(steps) <= 0).any():
        raise InvalidArgumentError(f"calibrate.times: samples closer than the world's step "
                                   f"({dt:g} s) cannot be told apart")
    return Observation(names, steps, poses[1:, :, :3].copy())


def start_twists(times: np.ndarray, poses: np.ndarray, dt: float) -> np.ndarray:
    """Each body's twist at the first sample: linear from the parabola through its first
    three positions (two: the difference), angular from the rotation between its first two
    orientations. A body not seen then starts at rest.

    The engines integrate semi-implicitly (the velocity first, then the position with it),
    so under a constant acceleration a the positions lie on a parabola whose slope at the
    start is the velocity plus a dt / 2: that half step is taken off."""
    count = poses.shape[1]
    twists = np.zeros((count, 6))
    for body in range(count):
        seen = np.flatnonzero(~np.isnan(poses[:, body, 0]))[:3]
        if len(seen) < 2 or seen[0] != 0:
            continue
        t, p = times[seen], poses[seen, body, :3]
        slope, curvature = _derivatives_at_start(t, p)
        twists[body, :3] = slope - curvature * dt / 2
        twists[body, 3:] = _angular(poses[seen[0], body, 3:], poses[seen[1], body, 3:],
                                    t[1] - t[0])
    return twists


def _derivatives_at_start(t: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The first and second derivatives at t0 of the quadratic through the points (of the
    line through two: no curvature)."""
    if len(t) == 2:
        slope: np.ndarray = (p[1] - p[0]) / (t[1] - t[0])
        return slope, np.zeros(3)
    h1, h2 = t[1] - t[0], t[2] - t[0]
    # Lagrange: d/dt at t0 of the quadratic through (t0, p0), (t1, p1), (t2, p2).
    derivative: np.ndarray = (-(h1 + h2) / (h1 * h2) * p[0] + h2 / (h1 * (h2 - h1)) * p[1]
                              - h1 / (h2 * (h2 - h1)) * p[2])
    curvature: np.ndarray = 2 * (p[0] / (h1 * h2) - p[1] / (h1 * (h2 - h1))
                                 + p[2] / (h2 * (h2 - h1)))
    return derivative, curvature


def _angular(q0: np.ndarray, q1: np.ndarray, seconds: float) -> np.ndarray:
    """The world-frame angular velocity turning q0 into q1 (x, y, z, w) in ``seconds``."""
    x0, y0, z0, w0 = q0 / np.linalg.norm(q0)
    inverse = np.array([-x0, -y0, -z0, w0])
    delta = _product(q1 / np.linalg.norm(q1), inverse)
    if delta[3] < 0:
        delta = -delta
    sine = float(np.linalg.norm(delta[:3]))
    if sine < 1e-12:
        return np.zeros(3)
    angle = 2.0 * np.arctan2(sine, delta[3])
    rate: np.ndarray = delta[:3] / sine * angle / seconds
    return rate


def _product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])
