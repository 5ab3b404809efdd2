"""Exact ray hits on the protocol's primitives, in each body's own frame.

Bullet casts a ray at a sphere, capsule or cylinder by a convex cast that stops within its
tolerance: a ray at a 0.1 m sphere lands 4e-4 m off the surface, with a tilted normal. The
engine contract wants the same answers as MuJoCo's exact ray tests, so a hit on a spawned
primitive is computed again here from the body's pose and size: the first surface point at
t >= 0 along the ray (from inside a body: where the ray leaves it, which the caller
skips), with the outward
normal there; a plane's hits are exact already, but Bullet's is seen from both sides.
Each function takes local origins and unit directions (n, 3) and returns the
distances (n,), inf where the ray misses, and local normals (n, 3).
"""

from __future__ import annotations

import numpy as np

Hits = tuple[np.ndarray, np.ndarray]  # distances (n,), normals (n, 3)
# Slack on a face's bounds, so that a ray through an edge or a rim is not lost to rounding.
EDGE_SLACK = 1e-12


def _first(ts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest candidate t >= 0 per row (inf when none) and its column."""
    ts = np.where(ts >= 0.0, ts, np.inf)
    column = np.argmin(ts, axis=1)
    return ts[np.arange(len(ts)), column], column


def _point(o: np.ndarray, d: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The points at t along the rays (the origin where t is inf: a miss)."""
    point: np.ndarray = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
    return point


def _quadratic(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both roots of a t^2 + 2 b t + c = 0 (NaN where none, or a = 0)."""
    with np.errstate(invalid="ignore", divide="ignore"):
        root = np.sqrt(b * b - a * c)
        return (-b - root) / a, (-b + root) / a


def sphere(o: np.ndarray, d: np.ndarray, size: np.ndarray) -> Hits:
    r = size[:, 0]
    near, far = _quadratic(np.ones(len(o)), np.sum(o * d, axis=1),
                           np.sum(o * o, axis=1) - r * r)
    t, _ = _first(np.nan_to_num(np.stack([near, far], axis=1), nan=-1.0))
    return t, _point(o, d, t) / r[:, None]


def box(o: np.ndarray, d: np.ndarray, size: np.ndarray) -> Hits:
    """Six faces: a face's t counts where the point lies within the other two extents."""
    n = len(o)
    ts = np.full((n, 6), -1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        for axis in range(3):
            for side, sign in enumerate((-1.0, 1.0)):
                t = (sign * size[:, axis] - o[:, axis]) / d[:, axis]
                p = o + t[:, None] * d
                others = [k for k in range(3) if k != axis]
                inside = np.all(np.abs(p[:, others]) <= size[:, others] * (1 + EDGE_SLACK),
                                axis=1)
                ts[:, 2 * axis + side] = np.where(inside & np.isfinite(t), t, -1.0)
    t, column = _first(ts)
    normals = np.zeros((n, 3))
    normals[np.arange(n), column // 2] = np.where(column % 2 == 1, 1.0, -1.0)
    return t, normals


def _side(o: np.ndarray, d: np.ndarray, r: np.ndarray, half: np.ndarray) -> np.ndarray:
    """Both crossings of the infinite side |xy| = r, kept where |z| <= half (n, 2)."""
    near, far = _quadratic(d[:, 0] ** 2 + d[:, 1] ** 2, o[:, 0] * d[:, 0] + o[:, 1] * d[:, 1],
                           o[:, 0] ** 2 + o[:, 1] ** 2 - r * r)
    ts = np.stack([near, far], axis=1)
    z = o[:, 2:3] + ts * d[:, 2:3]
    return np.where(np.abs(z) <= half[:, None] * (1 + EDGE_SLACK), ts, -1.0)


def _side_normals(p: np.ndarray, r: np.ndarray) -> np.ndarray:
    normals = np.zeros_like(p)
    normals[:, :2] = p[:, :2] / r[:, None]
    return normals


def cylinder(o: np.ndarray, d: np.ndarray, size: np.ndarray) -> Hits:
    r, half = size[:, 0], size[:, 1]
    caps = np.full((len(o), 2), -1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        for k, sign in enumerate((-1.0, 1.0)):
            t = (sign * half - o[:, 2]) / d[:, 2]
            p = o + t[:, None] * d
            within = p[:, 0] ** 2 + p[:, 1] ** 2 <= (r * r) * (1 + EDGE_SLACK)
            caps[:, k] = np.where(within & np.isfinite(t), t, -1.0)
    ts = np.nan_to_num(np.hstack([_side(o, d, r, half), caps]), nan=-1.0)
    t, column = _first(ts)
    normals = _side_normals(_point(o, d, t), r)
    on_cap = column >= 2
    normals[on_cap] = 0.0
    normals[on_cap, 2] = np.where(column[on_cap] == 3, 1.0, -1.0)
    return t, normals


def capsule(o: np.ndarray, d: np.ndarray, size: np.ndarray) -> Hits:
    """The side between the caps' centres, and two spheres, each kept beyond its centre."""
    r, half = size[:, 0], size[:, 1]
    columns = [_side(o, d, r, half)]
    centres = []
    for sign in (-1.0, 1.0):
        centre = np.zeros_like(o)
        centre[:, 2] = sign * half
        centres.append(centre)
        rel = o - centre
        near, far = _quadratic(np.ones(len(o)), np.sum(rel * d, axis=1),
                               np.sum(rel * rel, axis=1) - r * r)
        ts = np.stack([near, far], axis=1)
        beyond = sign * (rel[:, 2:3] + ts * d[:, 2:3]) >= 0.0
        columns.append(np.where(beyond, ts, -1.0))
    t, column = _first(np.nan_to_num(np.hstack(columns), nan=-1.0))
    p = _point(o, d, t)
    normals = _side_normals(p, r)
    for k, centre in enumerate(centres):
        cap = column // 2 == k + 1
        normals[cap] = (p[cap] - centre[cap]) / r[cap, None]
    return t, normals


def plane(o: np.ndarray, d: np.ndarray, size: np.ndarray) -> Hits:
    """Infinite, and seen from its front only (z >= 0), as MuJoCo's rays see a plane:
    Bullet's is seen from both sides."""
    with np.errstate(invalid="ignore", divide="ignore"):
        t = -o[:, 2] / d[:, 2]
    t = np.where((o[:, 2] >= 0.0) & (d[:, 2] < 0.0), t, np.inf)
    normals = np.zeros_like(o)
    normals[:, 2] = 1.0
    return t, normals


EXACT = {"sphere": sphere, "box": box, "cylinder": cylinder, "capsule": capsule,
         "plane": plane}
