"""Ray casts in a PyBullet world: rayTestBatch finds what each ray hits first, and a hit on
a spawned primitive is made exact (ray_shapes.py).

rayTestBatch takes fewer than ``pybullet.MAX_RAY_INTERSECTION_BATCH_SIZE`` rays a call, so
a longer batch goes in chunks; it reports a hit as the fraction of the ray from its start to
its end, which is a distance once multiplied by the ray's length. Where Bullet's looser
cast grazes a primitive that the exact test misses, the ray goes on from where it leaves a
sphere round that body (a little wider than it), at most ``REGRAZE_TRIES`` times; a body
reaching into that sphere, behind the grazed one, is then missed, and a ray that only the
exact test would graze misses: both need a ray within Bullet's tolerance of a surface
(4e-4 m on a 0.1 m sphere). A ray that meets a plane from behind goes on past it.

A ray does not see a shape it starts inside (docs/protocol.md, ``raycast``): Bullet's rays
see a convex shape from outside only, and go on to what lies beyond. But Bullet reports the
shape a ray starts in when a shape nested in it is hit first (its search, bounded by that
hit, then lies wholly inside): for a spawned primitive that is found by the exact test (the
ray meets its surface leaving it), and the ray's hits are then listed one by one
(``_nearest_outside``). Should the exact test still find a ray leaving a primitive, the ray
goes on from just past that point, as MuJoCo's engine does (perception.py).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.frames import conjugate, rotate
from galton.daemon.engines.pybullet.ray_shapes import EXACT
from galton.protocol import OperationFailedError

# rayTestBatch refuses more than its maximum, and at exactly the maximum answers one ray
# short (from lists) or not at all (from arrays): one less is what it takes whole.
BATCH = int(getattr(pybullet, "MAX_RAY_INTERSECTION_BATCH_SIZE", 256)) - 1
REGRAZE_TRIES = 3
MAX_HITS = 8  # hits listed for a ray Bullet answers with a shape it starts inside
STEP_PAST = 1e-9  # m past the surface a ray leaves, where it is cast again
BOUND_SLACK = 0.02  # wider than Bullet's shapes stand out (5e-4 m on a 0.1 m sphere)
Primitive = tuple[str, tuple[float, ...]]  # a spawned body's shape and half sizes
Rays = tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]


def raycast(bc: BulletClient, codes: Mapping[int, str], primitives: Mapping[int, Primitive],
            origins: np.ndarray, directions: np.ndarray, max_length: float) -> Rays:
    """Hits (n,), entity names ("" for a miss), points, normals (n, 3) and distances (n,),
    NaN where a ray misses; ``codes`` name PyBullet's (body, link) codes (render)."""
    origins = np.asarray(origins, float).reshape(-1, 3)
    directions = np.asarray(directions, float).reshape(-1, 3)
    n = len(origins)
    found = np.full(n, -1, np.int64)
    points, normals, distances = np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full(
        n, np.nan)
    todo = np.arange(n)
    starts, lengths = origins.copy(), np.full(n, float(max_length))
    for _ in range(REGRAZE_TRIES + 1):
        if not len(todo):
            break
        hit_code, distance, point, normal = _bullet(bc, starts[todo], directions[todo],
                                                    lengths[todo])
        # Bullet reports a shape the ray starts in at the start itself (fraction 0).
        at_start = np.flatnonzero((hit_code >= 0) & (distance <= STEP_PAST))
        inside = at_start[_leaves(bc, primitives, hit_code[at_start], starts[todo][at_start],
                                  directions[todo][at_start])]
        if len(inside):
            _nearest_outside(bc, primitives, inside, starts[todo], directions[todo],
                             lengths[todo], (hit_code, distance, point, normal))
        travelled = max_length - lengths[todo]
        again = _exact(bc, primitives, hit_code, starts[todo], directions[todo], lengths[todo],
                       distance, point, normal)
        done = (hit_code >= 0) & ~again
        rows = todo[done]
        found[rows] = hit_code[done]
        distances[rows] = travelled[done] + distance[done]
        points[rows], normals[rows] = point[done], normal[done]
        todo, skip = todo[again], distance[again]
        starts[todo] += directions[todo] * skip[:, None]
        lengths[todo] -= skip
        todo = todo[lengths[todo] > 0.0]
    return found >= 0, _names(codes, found), points, normals, distances


def _names(codes: Mapping[int, str], found: np.ndarray) -> list[str]:
    """Each ray's entity name ("" for none), looked up once per code."""
    unique, inverse = np.unique(found, return_inverse=True)
    names = np.array([codes.get(int(c), "") for c in unique], dtype=object)
    listed: list[str] = names[inverse.reshape(-1)].tolist()
    return listed


def _leaves(bc: BulletClient, primitives: Mapping[int, Primitive], code: np.ndarray,
            starts: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Whether each ray starts inside the spawned primitive its code names (the exact test
    meets that shape's surface first where the ray leaves it)."""
    out = np.zeros(len(code), bool)
    for c in np.unique(code).tolist():
        if c not in primitives:
            continue
        rows = np.flatnonzero(code == c)
        kind, size = primitives[c]
        position, orientation = bc.getBasePositionAndOrientation(c)
        turn_back = conjugate(np.tile(np.asarray(orientation, float), (len(rows), 1)))
        o = rotate(turn_back, starts[rows] - np.asarray(position, float))
        d = rotate(turn_back, directions[rows])
        t, local = EXACT[kind](o, d, np.tile(np.asarray(size, float), (len(rows), 1)))
        out[rows] = np.isfinite(t) & (np.sum(local * d, axis=1) > 0.0)
    return out


def _nearest_outside(bc: BulletClient, primitives: Mapping[int, Primitive], rows: np.ndarray,
                     starts: np.ndarray, directions: np.ndarray, lengths: np.ndarray,
                     answer: tuple[np.ndarray, ...]) -> None:
    """Bullet reports a shape a ray starts inside when a nearer hit (a shape nested in it)
    bounds its search within that shape: such rays have their hits listed one by one
    (at most MAX_HITS) and keep the nearest on a shape they do not start in (``answer``,
    Bullet's code, distance, point and normal, changed in place)."""
    start, direction, length = starts[rows], directions[rows], lengths[rows]
    best = np.full(len(rows), np.inf)
    code, point, normal = np.full(len(rows), -1), np.zeros((len(rows), 3)), np.zeros(
        (len(rows), 3))
    for k in range(MAX_HITS):
        c, dist, p, n = _bullet(bc, start, direction, length, report=k)
        if not (c >= 0).any():
            break
        better = (c >= 0) & (dist < best)
        better[better] = ~_leaves(bc, primitives, c[better], start[better], direction[better])
        best[better], code[better], point[better], normal[better] = (
            dist[better], c[better], p[better], n[better])
    hit_code, distance, points, normals = answer
    hit_code[rows], points[rows], normals[rows] = code, point, normal
    distance[rows] = np.where(code >= 0, best, length)


def _bullet(bc: BulletClient, origins: np.ndarray, directions: np.ndarray,
            lengths: np.ndarray, report: int | None = None
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bullet's answer per ray: the code hit (-1: none), distance, point and normal (the
    nearest hit, or with ``report`` the hit of that index in Bullet's list of all)."""
    ends = origins + directions * lengths[:, None]
    extra = {} if report is None else {"reportHitNumber": report}
    results: list[Any] = []
    for first in range(0, len(origins), BATCH):
        results.extend(bc.rayTestBatch(origins[first:first + BATCH],
                                       ends[first:first + BATCH], **extra))
    n = len(results)
    if n != len(origins):
        raise OperationFailedError(f"PyBullet rayTestBatch answered {n} of {len(origins)} rays")
    if not n:
        return np.zeros(0, np.int64), np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3))
    uids, links, fractions, points, normals = zip(*results, strict=True)
    flat = itertools.chain.from_iterable
    uid, link = np.fromiter(uids, np.int64, n), np.fromiter(links, np.int64, n)
    hit_code = np.where(uid >= 0, uid + ((link + 1) << 24), -1)
    return (hit_code, np.fromiter(fractions, np.float64, n) * lengths,
            np.fromiter(flat(points), np.float64, 3 * n).reshape(n, 3),
            np.fromiter(flat(normals), np.float64, 3 * n).reshape(n, 3))


def _exact(bc: BulletClient, primitives: Mapping[int, Primitive], hit_code: np.ndarray,
           origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray,
           distance: np.ndarray, point: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Hits on primitives made exact in place; True for rays to cast again (their
    ``distance`` set to where the grazed body's bounding sphere ends). Each body hit is
    looked up once, and each shape's rays are done together."""
    again = np.zeros(len(hit_code), bool)
    codes, which = np.unique(hit_code, return_inverse=True)
    found = [int(c) for c in codes if int(c) in primitives]
    if not found:
        return again
    shapes = sorted({primitives[c][0] for c in found})
    shape_of, sizes, poses = np.full(len(codes), -1), np.zeros((len(codes), 3)), np.zeros(
        (len(codes), 7))
    for k, c in enumerate(codes.tolist()):
        if c in primitives:
            kind, half_sizes = primitives[c]
            shape_of[k], sizes[k, :len(half_sizes)] = shapes.index(kind), half_sizes
            position, orientation = bc.getBasePositionAndOrientation(c)
            poses[k] = (*position, *orientation)
    ray_shape = shape_of[which.reshape(-1)]
    for s, shape in enumerate(shapes):
        rows = np.flatnonzero(ray_shape == s)
        body = which.reshape(-1)[rows]
        pose, size = poses[body], sizes[body]
        turn_back = conjugate(pose[:, 3:])
        o = rotate(turn_back, origins[rows] - pose[:, :3])
        d = rotate(turn_back, directions[rows])
        t, local = EXACT[shape](o, d, size)
        good = np.isfinite(t) & (t <= lengths[rows])
        leaving = good & (np.sum(local * d, axis=1) > 0.0)  # it started inside: unseen
        good &= ~leaving
        hit_rows = rows[good]
        distance[hit_rows] = t[good]
        point[hit_rows] = origins[hit_rows] + directions[hit_rows] * t[good, None]
        normal[hit_rows] = rotate(pose[good, 3:], local[good])
        miss_rows = rows[~good]
        again[miss_rows] = True
        distance[miss_rows] = _beyond(shape, o[~good], d[~good], size[~good])
        distance[rows[leaving]] = t[leaving] + STEP_PAST
    return again


def _beyond(shape: str, o: np.ndarray, d: np.ndarray, size: np.ndarray) -> np.ndarray:
    """How far along each ray it leaves a sphere round the body, ``BOUND_SLACK`` wider than
    the body, so that Bullet's looser shape is behind it."""
    if shape == "plane":  # seen from behind: on from just past it
        with np.errstate(invalid="ignore", divide="ignore"):
            crossing = np.nan_to_num(-o[:, 2] / d[:, 2], nan=0.0, posinf=0.0, neginf=0.0)
        past: np.ndarray = np.maximum(crossing, 0.0) * (1.0 + 1e-12) + 1e-12
        return past
    radius = (np.sum(size, axis=1) if shape == "capsule" else np.linalg.norm(size, axis=1))
    radius = radius * (1.0 + BOUND_SLACK)
    closest = -np.sum(o * d, axis=1)
    off_axis = np.sum(o * o, axis=1) - closest * closest
    ahead: np.ndarray = closest + np.sqrt(np.maximum(radius * radius - off_axis, 0.0))
    clipped: np.ndarray = np.maximum(ahead, 0.0)
    return clipped
