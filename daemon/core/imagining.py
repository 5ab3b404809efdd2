"""What ``predict`` imagines beyond one future: how many futures, each one's perturbed
start (seeded noise on the bodies' poses and velocities) and its plan (timed joint
targets and wrenches), turned into the specs of daemon/world/futures.py."""

from __future__ import annotations

import math
import secrets
from collections.abc import Callable

import numpy as np

from galton.daemon.ops import joints as ops_joints
from galton.daemon.world.futures import Action, FutureSpec
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError
from galton.protocol import requests as rq


def future_count(request: rq.Predict) -> int:
    """``futures``, or one per plan; refused when the two disagree."""
    plans = request.plans
    count = request.futures or (len(plans) if plans else 1)
    if plans is not None and len(plans) != count:
        raise InvalidArgumentError(f"predict.plans gives {len(plans)} plans for {count} "
                                   "futures: give one plan per future")
    return count


def specs(world: World, request: rq.Predict, count: int, steps: int, dt: float
          ) -> tuple[list[FutureSpec], int | None]:
    """One spec per future, and the seed its noise was drawn with (None: no noise)."""
    if request.score is not None:
        world.require_known([request.score.body])
    plans = [_plan(world, plan, index, steps, dt) for index, plan in
             enumerate(request.plans or [])] or [[] for _ in range(count)]
    noise = _noisy_bodies(world, request.perturb)
    if not noise:
        return [FutureSpec(events=plan) for plan in plans], None
    seed = secrets.randbits(63) if request.seed is None else request.seed
    rng = np.random.default_rng(seed)
    names = list(noise)
    sigmas = np.array([noise[n] for n in names])  # (bodies, 3)
    _skip(rng, request.first_future * _DRAWS_PER_BODY * len(names))
    starts = [_perturbed(names, sigmas, rng) for _ in range(count)]
    return [FutureSpec(start=start, events=plan) for start, plan in
            zip(starts, plans, strict=True)], seed


_DRAWS_PER_BODY = 9  # a future's normals per noisy body: shift, turn, push (3 axes each)
_SKIP_CHUNK = 1 << 20


def _skip(rng: np.random.Generator, draws: int) -> None:
    """Pass over the normals of the futures before ``first_future`` (drawn and dropped, in
    chunks): a future's noise is then the same whichever batch of the ensemble it is in."""
    while draws > 0:
        rng.standard_normal(min(draws, _SKIP_CHUNK))
        draws -= _SKIP_CHUNK


def _noisy_bodies(world: World, perturb: rq.Perturb | None) -> dict[str, tuple[float, ...]]:
    """Body -> (position, orientation, velocity) sigmas, for bodies with any noise."""
    if perturb is None:
        return {}
    own = perturb.bodies or {}
    world.require_known(list(own))
    everyone = (perturb.position, perturb.orientation, perturb.velocity)
    out = {}
    if any(everyone):
        out = {n: everyone for n, e in world.entities.items()
               if not e.info.static and e.info.shape not in ("model", "link")}
    for name, s in own.items():
        out[name] = (s.position, s.orientation, s.velocity)
    return {n: s for n, s in out.items() if any(s)}


def _perturbed(names: list[str], sigmas: np.ndarray, rng: np.random.Generator) -> Action:
    """A start that adds this future's noise (drawn now, in order) to the bodies' states."""
    count = len(names)
    shift = rng.normal(0.0, 1.0, (count, 3)) * sigmas[:, :1]
    turn = rng.normal(0.0, 1.0, (count, 3)) * sigmas[:, 1:2]
    push = rng.normal(0.0, 1.0, (count, 3)) * sigmas[:, 2:3]

    def start(world: World) -> None:
        poses, twists = world.engine.get_states(names)
        poses = poses.copy()
        twists = twists.copy()
        poses[:, :3] += shift
        poses[:, 3:] = _rotated(poses[:, 3:], turn)
        twists[:, :3] += push
        world.set_states(names, poses, twists)
    return start


def _rotated(quats: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Each (x, y, z, w) quaternion turned by its rotation vector, in the world frame."""
    angle = np.linalg.norm(vectors, axis=1)
    half = angle / 2.0
    axis = np.divide(vectors, angle[:, None], out=np.zeros_like(vectors),
                     where=angle[:, None] > 0)
    dq = np.hstack([axis * np.sin(half)[:, None], np.cos(half)[:, None]])
    x1, y1, z1, w1 = dq.T
    x2, y2, z2, w2 = quats.T
    out = np.stack([w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                    w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2,
                    w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2,
                    w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2], axis=1)
    unit: np.ndarray = out / np.linalg.norm(out, axis=1, keepdims=True)
    return unit


def _plan(world: World, plan: list[rq.PlanStep], index: int, steps: int, dt: float
          ) -> list[tuple[int, Action]]:
    """A plan's timed actions at whole steps (rounded up), each decoded now: refused
    before a step when one is malformed or at or past the horizon."""
    events = []
    for number, item in enumerate(plan):
        where = f"predict.plans[{index}][{number}]"
        at = math.ceil(item.at / dt - 1e-9)
        if at >= steps:
            raise InvalidArgumentError(f"{where}.at {item.at:g} s is at or past the "
                                       f"horizon ({steps} steps of {dt:g} s)")
        if item.joint_targets is None and item.wrenches is None:
            raise InvalidArgumentError(f"{where} gives neither joint_targets nor wrenches")
        events.append((at, _action(item, where)))
    return events


def _action(item: rq.PlanStep, where: str) -> Action:
    actions: list[Callable[[World], object]] = []
    if item.joint_targets is not None:
        targets = rq.decode_args("set_joint_targets", rq.SetJointTargets, item.joint_targets)
        actions.append(lambda w: ops_joints.set_joint_targets(w, targets))
    if item.wrenches is not None:
        wrenches = rq.decode_args("apply_wrench", rq.ApplyWrench, item.wrenches)
        actions.append(lambda w: ops_joints.apply_wrench(w, wrenches))

    def act(world: World) -> None:
        for action in actions:
            action(world)
    return act
