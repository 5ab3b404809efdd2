"""compare: observed poses (and twists) of named bodies against the world's, as errors and
one anomaly score (docs/protocol.md, "compare"), optionally correcting the world."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from galton.daemon.world.surprise import Sample
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError, pack_f64
from galton.protocol import requests as rq
from galton.protocol.model import (
    check_names,
    decode_poses,
    decode_twists,
    decode_values,
)


def angle_between(q1: np.ndarray, q2: np.ndarray) -> np.ndarray:
    """The angle (rad) of the rotation taking each unit quaternion of q1 to q2's."""
    dots = np.abs(np.sum(q1 * q2, axis=1)).clip(0.0, 1.0)
    angles: np.ndarray = 2.0 * np.arccos(dots)
    return angles


def _expected_position_sigmas(spread: float | bytes | None, count: int,
                               sigma_p: float) -> np.ndarray | float:
    """How far each observed position may be expected to lie from the world's: the
    measurement noise ``sigma_position`` alone, or combined with the spread an ensemble
    prediction gave (independent errors: their variances add)."""
    if spread is None:
        return sigma_p
    values = decode_values(spread, count, "compare.spread",
                           bound=rq.value_bound(rq.Compare, "spread"))
    if (values < 0).any():
        raise InvalidArgumentError(f"compare.spread[{int(np.argmax(values < 0))}] is "
                                   "negative: a spread is a standard deviation, at least 0")
    sigmas: np.ndarray = np.sqrt(values ** 2 + sigma_p ** 2)
    return sigmas


def compare(world: World, request: rq.Compare) -> dict[str, Any]:
    names = check_names(request.names, "compare.names")
    observed = decode_poses(request.poses, len(names), "compare.poses")
    raw_twists = request.twists
    twists = None if raw_twists is None else decode_twists(raw_twists, len(names),
                                                           "compare.twists")
    sigma_p, sigma_a, sigma_v = request.sigma_position, request.sigma_angle, request.sigma_speed
    correct = request.correct
    poses, world_twists = world.get_states(names)
    position_errors = np.linalg.norm(observed[:, :3] - poses[:, :3], axis=1)
    angle_errors = angle_between(observed[:, 3:7], poses[:, 3:7])
    expected = _expected_position_sigmas(request.spread, len(names), sigma_p)
    terms = (position_errors / expected) ** 2 + (angle_errors / sigma_a) ** 2
    result: dict[str, Any] = {"position_errors": pack_f64(position_errors),
                              "angle_errors": pack_f64(angle_errors)}
    if twists is not None:
        speed_errors = np.linalg.norm(twists[:, :3] - world_twists[:, :3], axis=1)
        terms = terms + (speed_errors / sigma_v) ** 2
        result["speed_errors"] = pack_f64(speed_errors)
    result["score"] = math.sqrt(float(np.mean(terms)))
    if correct:
        world.set_states(names, observed, twists)
    result["corrected"] = correct
    trigger = request.trigger
    if trigger is not None:  # counted after the comparison, which a bad argument refuses
        kept = None if trigger.calibrate is None else Sample(
            world.sim_time, tuple(names), observed.copy(),
            None if twists is None else twists.copy())
        result["suggested"] = world.surprise.observe(result["score"], trigger.threshold,
                                                     trigger.window, world.sim_time, kept)
        result["streak"] = world.surprise.count
    return result
