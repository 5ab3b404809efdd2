"""Ray casts in a PyBullet world: rayTestBatch finds what each ray hits first, and a hit on
a spawned primitive is made exact (pybullet_rayshapes.py).

rayTestBatch takes fewer than ``pybullet.MAX_RAY_INTERSECTION_BATCH_SIZE`` rays a call, so
a longer batch goes in chunks; it reports a hit as the fraction of the ray from its start to
its end, which is a distance once multiplied by the ray's length. Where Bullet's looser
cast grazes a primitive that the exact test misses, the ray goes on from where it leaves a
sphere round that body (a little wider than it), at most ``REGRAZE_TRIES`` times; a body
reaching into that sphere, behind the grazed one, is then missed, and a ray that only the
exact test would graze misses: both need a ray within Bullet's tolerance of a surface
(4e-4 m on a 0.1 m sphere). A ray that meets a plane from behind goes on past it.

A ray does not see a shape it starts inside (docs/protocol.md, ``raycast``): Bullet's rays
see a convex shape from outside only, and where the exact test finds a ray leaving a
primitive, it goes on from just past that point (MuJoCo's engine does the same,
mujoco_sensing.py).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from typing import Any

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet_frames import conjugate, rotate
from galton.daemon.engines.pybullet_rayshapes import EXACT, INSIDE
from galton.protocol import OperationFailedError

# rayTestBatch refuses more than its maximum, and at exactly the maximum answers one ray
# short (from lists) or not at all (from arrays): one less is what it takes whole.
BATCH = int(getattr(pybullet, "MAX_RAY_INTERSECTION_BATCH_SIZE", 256)) - 1
REGRAZE_TRIES = 3
EXIT_TRIES = 8  # shapes inside shapes a ray starts in
STEP_PAST = 1e-9  # m past the surface a ray leaves, where it is cast again
BOUND_SLACK = 0.02  # wider than Bullet's shapes stand out (5e-4 m on a 0.1 m sphere)
Primitive = tuple[str, tuple[float, ...]]  # a spawned body's shape and half sizes
Rays = tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]


def raycast(bc: BulletClient, codes: Mapping[int, str], primitives: Mapping[int, Primitive],
            origins: np.ndarray, directions: np.ndarray, max_length: float) -> Rays:
    """Hits (n,), entity names ("" for a miss), points, normals (n, 3) and distances (n,),
    NaN where a ray misses; ``codes`` name PyBullet's (body, link) codes (pybullet_render)."""
    origins = np.asarray(origins, float).reshape(-1, 3)
    directions = np.asarray(directions, float).reshape(-1, 3)
    n = len(origins)
    found = np.full(n, -1, np.int64)
    points, normals, distances = np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full(
        n, np.nan)
    starts, lengths = origins.copy(), np.full(n, float(max_length))
    todo = np.arange(n)
    for _ in range(EXIT_TRIES + 1):
        hit = _trace(bc, primitives, todo, starts, directions, lengths, max_length)
        for row, (code, distance, point, normal) in hit.items():
            found[row], distances[row], points[row], normals[row] = code, distance, point, normal
        todo = _leave_primitives(bc, primitives, todo[found[todo] < 0], starts, directions,
                                 lengths)
        if not len(todo):
            break
    return found >= 0, _names(codes, found), points, normals, distances


Hit = tuple[int, float, np.ndarray, np.ndarray]  # code, distance, point, normal


def _trace(bc: BulletClient, primitives: Mapping[int, Primitive], todo: np.ndarray,
           starts: np.ndarray, directions: np.ndarray, lengths: np.ndarray,
           max_length: float) -> dict[int, Hit]:
    """Bullet's hits for these rows, made exact, grazes cast again (``starts`` and
    ``lengths`` move on with them)."""
    hits: dict[int, Hit] = {}
    for _ in range(REGRAZE_TRIES + 1):
        if not len(todo):
            break
        hit_code, distance, point, normal = _bullet(bc, starts[todo], directions[todo],
                                                    lengths[todo])
        travelled = max_length - lengths[todo]
        again = _exact(bc, primitives, hit_code, starts[todo], directions[todo], lengths[todo],
                       distance, point, normal)
        done = np.flatnonzero((hit_code >= 0) & ~again)
        for k in done.tolist():
            hits[int(todo[k])] = (int(hit_code[k]), float(travelled[k] + distance[k]),
                                  point[k], normal[k])
        todo, skip = todo[again], distance[again]
        starts[todo] += directions[todo] * skip[:, None]
        lengths[todo] -= skip
        todo = todo[lengths[todo] > 0.0]
    return hits


def _leave_primitives(bc: BulletClient, primitives: Mapping[int, Primitive],
                      rows: np.ndarray, starts: np.ndarray, directions: np.ndarray,
                      lengths: np.ndarray) -> np.ndarray:
    """Rays that missed because they start inside a spawned primitive (Bullet then reports
    nothing at all along them) move on to where they leave it, plus BOUND_SLACK of its
    size (Bullet's skin); returns those rows. Only rays starting within the primitives'
    bounding box and hitting something when cast backwards from their end (one more
    batch) are looked at, each distinct start once in Bullet's broadphase."""
    if len(rows) and primitives:
        rows = rows[_near_primitives(bc, primitives, starts[rows])]
    if len(rows):  # a true miss is a miss backwards too: one batch
        back, _, _, _ = _bullet(bc, starts[rows] + directions[rows] * lengths[rows, None],
                                -directions[rows], lengths[rows])
        rows = rows[back >= 0]
    if not len(rows):
        return rows
    unique, inverse = np.unique(starts[rows], axis=0, return_inverse=True)
    container = np.array([_container(bc, primitives, p) for p in unique], np.int64)
    codes = container[inverse.reshape(-1)]
    moved = rows[codes >= 0]
    for code in np.unique(codes[codes >= 0]).tolist():
        these = rows[codes == code]
        kind, size = primitives[code]
        position, orientation = bc.getBasePositionAndOrientation(code)
        turn_back = conjugate(np.tile(orientation, (len(these), 1)))
        o = rotate(turn_back, starts[these] - np.asarray(position))
        d = rotate(turn_back, directions[these])
        t, _ = EXACT[kind](o, d, np.tile(np.asarray(size, float), (len(these), 1)))
        # Bullet's shape stands out a little: a ray starting on its skin is still inside it.
        skip = np.where(np.isfinite(t), t, 0.0) + BOUND_SLACK * max(size) + STEP_PAST
        starts[these] += directions[these] * skip[:, None]
        lengths[these] -= skip
    kept: np.ndarray = moved[lengths[moved] > 0.0]
    return kept


def _near_primitives(bc: BulletClient, primitives: Mapping[int, Primitive],
                     points: np.ndarray) -> np.ndarray:
    """Whether each point lies in the box bounding every spawned primitive but planes."""
    solid = [(code, size) for code, (kind, size) in primitives.items() if kind != "plane"]
    if not solid:
        return np.zeros(len(points), bool)
    centres = np.array([bc.getBasePositionAndOrientation(code)[0] for code, _ in solid])
    reach = np.array([float(np.linalg.norm(size)) for _, size in solid])[:, None]
    low, high = (centres - reach).min(axis=0), (centres + reach).max(axis=0)
    near: np.ndarray = np.all((points >= low) & (points <= high), axis=1)
    return near


def _container(bc: BulletClient, primitives: Mapping[int, Primitive], point: np.ndarray
               ) -> int:
    """The code of a spawned primitive holding ``point`` inside it, else -1."""
    for uid, link in bc.getOverlappingObjects(point - STEP_PAST, point + STEP_PAST) or ():
        code = uid + ((link + 1) << 24)
        if code in primitives:
            position, orientation = bc.getBasePositionAndOrientation(code)
            local = rotate(conjugate(np.array([orientation], float)),
                           np.array([point - np.asarray(position)]))[0]
            if INSIDE[primitives[code][0]](local, np.asarray(primitives[code][1], float)):
                return int(code)
    return -1


def _names(codes: Mapping[int, str], found: np.ndarray) -> list[str]:
    """Each ray's entity name ("" for none), looked up once per code."""
    unique, inverse = np.unique(found, return_inverse=True)
    names = np.array([codes.get(int(c), "") for c in unique], dtype=object)
    listed: list[str] = names[inverse.reshape(-1)].tolist()
    return listed


def _bullet(bc: BulletClient, origins: np.ndarray, directions: np.ndarray,
            lengths: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bullet's answer per ray: the code hit (-1: none), distance, point and normal."""
    ends = origins + directions * lengths[:, None]
    results: list[Any] = []
    for first in range(0, len(origins), BATCH):
        results.extend(bc.rayTestBatch(origins[first:first + BATCH],
                                       ends[first:first + BATCH]))
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
