"""predict: run ahead on a copy of a world (its present, or a snapshot slot), optionally
changed first, sampling named bodies and joints, then discard the copy. The copy is
stepped as a side job (daemon/core/side_jobs.py), after the live world's due steps."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from galton.daemon.core import imagining
from galton.daemon.core.calls import Call, StepJob
from galton.daemon.core.context import PredictContext
from galton.daemon.core.reply_limit import VALUE_BYTES, reads_size, require_room
from galton.daemon.ops import entities as ops
from galton.daemon.ops import joints as ops_joints
from galton.daemon.world import futures as fs
from galton.daemon.world.futures import FutureSet
from galton.daemon.world.snapshot import clone_of, decode, world_from
from galton.daemon.world.world import World
from galton.protocol import (
    IncorrectStateError,
    InvalidArgumentError,
    OperationFailedError,
)
from galton.protocol import requests as rq
from galton.protocol.arrays import pack_f64
from galton.protocol.model import check_names


@dataclass
class PredictSampler:
    """The samples of one prediction's futures: sim times, body states, joint states, and
    with a score each future's distance of a body to a point at the last sample."""

    every: int
    read: list[str] | None
    read_joints: list[str] | None
    futures: FutureSet
    score: rq.Score | None = None
    times: list[float] = field(default_factory=list)
    poses: list[np.ndarray] = field(default_factory=list)  # per sample (futures, bodies, 7)
    twists: list[np.ndarray] = field(default_factory=list)
    positions: list[np.ndarray] = field(default_factory=list)  # per sample (futures, joints)
    velocities: list[np.ndarray] = field(default_factory=list)
    scores: np.ndarray | None = None
    seed: int | None = None

    def take(self, world: World) -> None:
        self.futures.verify()
        self.times.append(world.sim_time)
        worlds = self.futures.worlds
        if self.read is not None:
            states = [w.get_states(self.read) for w in worlds]
            self.poses.append(np.stack([p for p, _ in states]))
            self.twists.append(np.stack([t for _, t in states]))
        if self.read_joints is not None:
            joints = [w.engine.get_joint_states(self.read_joints) for w in worlds]
            self.positions.append(np.stack([j[0] for j in joints]))
            self.velocities.append(np.stack([j[1] for j in joints]))
        if self.score is not None:
            where = self.futures.positions([self.score.body])[:, 0]
            self.scores = np.linalg.norm(where - np.array(self.score.target), axis=1)

    def result(self, steps: int) -> dict[str, Any]:
        count = len(self.futures)
        out: dict[str, Any] = {"steps": steps, "times": pack_f64(np.array(self.times))}
        if count > 1:
            out["futures"] = count
        if self.seed is not None:
            out["seed"] = self.seed
        if self.read is not None:
            poses = np.stack(self.poses, axis=1)  # (futures, samples, bodies, 7)
            out.update(names=self.read, poses=pack_f64(poses),
                       twists=pack_f64(np.stack(self.twists, axis=1)))
            if count > 1:
                out["spread"] = pack_f64(np.stack([fs.spread(p[:, :, :3])
                                                   for p in self.poses]))
        if self.read_joints is not None:
            out["joints"] = {"names": self.read_joints,
                             "positions": pack_f64(np.stack(self.positions, axis=1)),
                             "velocities": pack_f64(np.stack(self.velocities, axis=1))}
        if self.scores is not None:
            out["scores"] = pack_f64(self.scores)
        return out


def predict(ctx: PredictContext, call: Call, request: rq.Predict) -> None:
    """Start a prediction job (answered when its horizon is done)."""
    if ctx.job is not None:
        raise IncorrectStateError("another step request is still running; wait for it")
    if ctx.engine_factory is None:
        raise OperationFailedError("this daemon cannot make engines")
    horizon = request.horizon
    source = ctx.world_for(request)
    slot = request.slot
    name = f"{source.name}:prediction"
    if slot is None:
        source.verify()
        copy = clone_of(source, name, ctx.limits)
    else:
        factory = ctx.engine_factory
        copy = ctx.slots.world_of(ctx.slots.get(slot), name, lambda blob: world_from(
            decode(blob, ctx.limits, ctx.snapshot_key), factory, name, ctx.limits))
    try:
        job = _job(ctx, call, copy, horizon, request)
    except Exception:
        copy.engine.close()
        raise
    job.source = source
    ctx.start_job(job)


def _job(ctx: PredictContext, call: Call, copy: World, horizon: float,
         request: rq.Predict) -> StepJob:
    dt = copy.engine.timestep
    steps = horizon_steps(horizon, dt, ctx.limits.max_steps)
    every = 1 if request.every is None else sample_period(request.every, dt, steps)
    read = _names(request.read, "read")
    joints = _names(request.read_joints, "read_joints")
    if read is not None:
        copy.require_known(read)
    if joints is not None:
        copy.joints.require_scalar(joints, "predict.read_joints")
    count = imagining.future_count(request)
    _require_reply_room(ctx.limits.max_reply_bytes, count * (steps // every + 1), read,
                        joints)
    _apply_changes(copy, request)
    specs, seed = imagining.specs(copy, request, count, steps, dt)
    futures = FutureSet.fork(copy, specs, ctx.limits, ctx.limits.future_threads,
                             first=copy)
    try:
        sampler = PredictSampler(min(every, steps), read, joints, futures, request.score,
                                 seed=seed)
        sampler.take(copy)
    except Exception:
        futures.worlds, futures.events = futures.worlds[1:], futures.events[1:]
        futures.close()  # all but the first: the caller closes it
        raise
    return StepJob(call, steps, steps, world=copy, sampler=sampler, scratch=True,
                   futures=futures)


def _require_reply_room(limit: int, samples: int, read: list[str] | None,
                        joints: list[str] | None) -> None:
    """Refuse, before a step, a prediction whose reply would pass ``max_reply_bytes``:
    each sample is its time, a pose and a twist per body, two values per joint."""
    size = reads_size(read, joints, samples, joint_values=2) + samples * VALUE_BYTES
    require_room(f"this prediction's reply ({samples} samples)", size, limit,
                 "sample less often with 'every', read fewer bodies")


def horizon_steps(horizon: float, dt: float, max_steps: int) -> int:
    """A horizon as whole steps (rounded up), refused when under one step or over the limit
    (compared as floats first: an absurd horizon must not overflow the rounding)."""
    exact = horizon / dt - 1e-9
    if exact > max_steps:
        raise InvalidArgumentError(f"predict.horizon {horizon:g} s is {exact:.3g} steps; at "
                                   f"most {max_steps}", {"max_steps": max_steps})
    if horizon / dt < 1 - 1e-9:
        raise InvalidArgumentError(f"predict.horizon {horizon:g} s is less than one step of "
                                   f"{dt:g} s")
    return math.ceil(exact)


def sample_period(every_s: float, dt: float, steps: int) -> int:
    """``every`` seconds as whole steps: at least one, at most the whole horizon."""
    exact = every_s / dt
    return steps if exact >= steps else max(1, round(exact))


def _names(raw: list[str] | None, key: str) -> list[str] | None:
    return None if raw is None else check_names(raw, f"predict.{key}")


def _apply_changes(copy: World, request: rq.Predict) -> None:
    """The changes a prediction starts from, each decoded and checked as its own request
    would be."""
    if request.set_states is not None:
        ops.set_states(copy, rq.decode_args("set_states", rq.SetStates, request.set_states))
    if request.joint_targets is not None:
        ops_joints.set_joint_targets(copy, rq.decode_args(
            "set_joint_targets", rq.SetJointTargets, request.joint_targets))
    if request.wrenches is not None:
        ops_joints.apply_wrench(copy, rq.decode_args("apply_wrench", rq.ApplyWrench,
                                                     request.wrenches))
