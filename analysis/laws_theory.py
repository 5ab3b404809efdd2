"""Closed forms of the physical-law suite: what an exact rigid-body simulator would give.

Each function is the textbook answer for one experiment of ``galton.client.laws``; the
suite compares every engine's measured value with it. Pure numpy, no scipy: the complete
elliptic integral comes from the arithmetic-geometric mean.
"""

from __future__ import annotations

import math

import numpy as np

SOLID_SPHERE = 2.0 / 5.0  # I / (m r²) about a diameter
SOLID_CYLINDER = 1.0 / 2.0  # I / (m r²) about its axis


def fall_distance(g: float, t: float) -> float:
    """How far a body dropped from rest falls in ``t`` seconds: g t²/2."""
    return 0.5 * g * t * t


def projectile_height(vz: float, g: float, t: float) -> float:
    """Height gained after ``t`` seconds by a body launched upward at ``vz``: vz t − g t²/2."""
    return vz * t - 0.5 * g * t * t


def elliptic_k(k: float) -> float:
    """The complete elliptic integral of the first kind K(k), modulus ``k`` (0 <= k < 1),
    as π / (2 AGM(1, √(1 − k²)))."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    while abs(a - b) > 1e-15 * a:
        a, b = (a + b) / 2.0, math.sqrt(a * b)
    return math.pi / (2.0 * a)


def pendulum_period(pivot_inertia: float, mass: float, g: float, arm: float,
                    amplitude: float) -> float:
    """The exact period of a physical pendulum released at rest from ``amplitude`` rad:
    4 √(I / (m g d)) K(sin(θ₀/2)); at small amplitude 2π √(I / (m g d))."""
    root = math.sqrt(pivot_inertia / (mass * g * arm))
    return 4.0 * root * elliptic_k(math.sin(amplitude / 2.0))


def pendulum_energy(pivot_inertia: float, mass: float, g: float, arm: float,
                    angle: np.ndarray, rate: np.ndarray) -> np.ndarray:
    """A physical pendulum's energy ½ I ω² + m g d (1 − cos θ), zero hanging at rest."""
    return np.asarray(0.5 * pivot_inertia * rate**2 + mass * g * arm * (1.0 - np.cos(angle)),
                      dtype=float)


def rolling_acceleration(g: float, slope: float, inertia_ratio: float) -> float:
    """A body rolling without slipping down a slope: g sin θ / (1 + I/(m r²)); 5/7 g sin θ
    for a solid sphere, 2/3 g sin θ for a solid cylinder."""
    return g * math.sin(slope) / (1.0 + inertia_ratio)


def rolls_without_slipping(slope: float, friction: float, inertia_ratio: float) -> bool:
    """Whether friction ``μ`` can hold a roll: μ >= tan θ · k / (1 + k), k = I/(m r²)."""
    return friction >= math.tan(slope) * inertia_ratio / (1.0 + inertia_ratio)


def sliding_acceleration(g: float, slope: float, friction: float) -> float:
    """A block on a slope: 0 where it holds (tan θ <= μ), else g (sin θ − μ cos θ)."""
    if math.tan(slope) <= friction:
        return 0.0
    return g * (math.sin(slope) - friction * math.cos(slope))


def sliding_distance(speed: float, friction: float, g: float) -> float:
    """How far a body sliding at ``speed`` on level ground goes before it stops: v²/(2 μ g)."""
    return speed * speed / (2.0 * friction * g)


def rebound_height(drop: float, restitution: float) -> float:
    """The height a ball dropped from ``drop`` bounces back to: e² h."""
    return restitution * restitution * drop


def collision_speeds(m1: float, m2: float, v1: float, v2: float,
                     restitution: float) -> tuple[float, float]:
    """Velocities after a head-on collision along one line, conserving momentum, with the
    separation speed e times the approach speed."""
    total = m1 + m2
    p = m1 * v1 + m2 * v2
    after1 = (p + m2 * restitution * (v2 - v1)) / total
    after2 = (p + m1 * restitution * (v1 - v2)) / total
    return after1, after2


def box_inertia(mass: float, half_extents: tuple[float, float, float]) -> np.ndarray:
    """The principal moments of a solid box about its centre: m/3 (b² + c²) and so on."""
    a, b, c = half_extents
    return mass / 3.0 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])


def rotation_matrices(quaternions: np.ndarray) -> np.ndarray:
    """(n, 3, 3) rotation matrices of (n, 4) unit quaternions x y z w."""
    q = np.asarray(quaternions, dtype=float).reshape(-1, 4)
    x, y, z, w = q.T
    matrices: np.ndarray = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], -1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], -1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], -1),
    ], axis=1)
    return matrices


def angular_momentum(principal: np.ndarray, quaternions: np.ndarray,
                     spins: np.ndarray) -> np.ndarray:
    """(n, 3) world-frame angular momenta R I Rᵀ ω of a body with ``principal`` moments
    along its own axes, at these orientations and world-frame angular velocities."""
    rotations = rotation_matrices(quaternions)
    body_spin: np.ndarray = np.einsum("nji,nj->ni", rotations, np.asarray(spins, dtype=float))
    return np.asarray(np.einsum("nij,nj->ni", rotations, body_spin * principal), dtype=float)


def quaternion_about(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """The unit quaternion (x y z w) turning ``angle`` rad about ``axis``."""
    unit = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    return np.append(unit * math.sin(angle / 2.0), math.cos(angle / 2.0))


def quaternion_product(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a ⊗ b (x y z w): turn by b, then by a."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return np.array([aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx,
                     aw * bz + ax * by - ay * bx + az * bw,
                     aw * bw - ax * bx - ay * by - az * bz])
