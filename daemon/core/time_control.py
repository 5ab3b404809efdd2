"""Time-control operations of the physics loop: play, pause, stop, step, run_until, reset,
load_world.

The state machine: stopped → playing ⇄ paused, with step jobs while not playing. Each
operation takes its context ``ctx`` (the loop as core/context.py's ``TimeContext``), the
call and its typed request (protocol/requests.py), and
returns the reply's result map, or None when the reply comes later (a step job).
daemon/ops/time_control.py binds them to the operations of protocol/operations.py.
"""

from __future__ import annotations

import math
import time
from typing import Any

from galton.daemon.access import lease
from galton.daemon.core.calls import Call, RestCheck, StepJob
from galton.daemon.core.context import JobEnd, Jobs, OpContext, TimeContext
from galton.daemon.core.reply_limit import reads_size, require_room
from galton.daemon.core.step_queue import StepBusyError
from galton.daemon.world.world import World
from galton.protocol import (
    IncorrectStateError,
    InvalidArgumentError,
    OperationFailedError,
    SimStatus,
)
from galton.protocol import requests as rq
from galton.protocol.model import check_names, integer_in
from galton.protocol.vocabulary import SimState


def _rest_check(rest: rq.UntilRest | None, read: list[str] | None,
                timestep: float) -> RestCheck | None:
    """run_until's optional ``until_rest``: stop once the read bodies rest."""
    if rest is None:
        return None
    if read is None:
        raise InvalidArgumentError("run_until.until_rest needs 'read': the bodies that must rest")
    return RestCheck(rest.speed, max(1, round(rest.every / timestep)))


def status(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    world = ctx.world_for(request)
    if world is ctx.world:
        return ctx.status().to_wire()
    return side_status(ctx, world).to_wire()


def side_status(ctx: TimeContext, world: World) -> SimStatus:
    """A side world's status: it never plays."""
    return SimStatus(
        state=SimState.STOPPED if world.step_index == 0 else SimState.PAUSED,
        step=world.step_index, sim_time=world.sim_time, timestep=world.engine.timestep,
        target_rtf=0.0, rtf=0.0, entity_count=len(world.entities), engine=world.engine.name,
        instance=ctx.instance, world=world.name, faulted=world.faulted,
        controller=ctx.lease.controller, stepping=ctx.job is not None)


def _live_only(ctx: TimeContext, request: rq.Args, op: str) -> None:
    if ctx.world_for(request) is not ctx.world:
        raise IncorrectStateError(f"{op}: only the live world {ctx.world.name!r} plays; a "
                                  "side world moves by step and run_until")


def play(ctx: TimeContext, call: Call, request: rq.Play) -> dict[str, Any]:
    _live_only(ctx, request, "play")
    target = ctx.target_rtf if request.rtf is None else request.rtf
    if ctx.job is not None and ctx.job.world is None:
        raise IncorrectStateError("a step request is still running; wait for it or pause")
    ctx.world.require_valid()
    ctx.target_rtf = target
    ctx.set_state(SimState.PLAYING)
    return ctx.status().to_wire()


def set_rtf(ctx: TimeContext, call: Call, request: rq.SetRtf) -> dict[str, Any]:
    _live_only(ctx, request, "set_rtf")
    ctx.target_rtf = request.rtf
    ctx.pacer.anchor(time.monotonic(), ctx.world.sim_time, ctx.target_rtf)
    return ctx.status().to_wire()


def pause(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    world = ctx.world_for(request)
    _cancel_job_on(ctx, world, "paused")
    if world is not ctx.world:
        return side_status(ctx, world).to_wire()
    ctx.set_state(SimState.PAUSED)
    return ctx.status().to_wire()


def stop(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    """Pause and rewind: time to 0 and every entity back to the state it was created in."""
    world = ctx.world_for(request)
    _cancel_job_on(ctx, world, "stopped")
    world.reset("state")
    world.reset("time")
    if world is not ctx.world:
        return side_status(ctx, world).to_wire()
    _after_reset(ctx)
    ctx.set_state(SimState.STOPPED)
    return ctx.status().to_wire()


def step(ctx: TimeContext, call: Call, request: rq.Step) -> None:
    count = integer_in(request.count, "step.count", 1, ctx.limits.max_steps)
    world = ctx.world_for(request)
    _start_job(ctx, call, world, count, _read_list(world, request.read, "step"),
               read_joints=_read_joint_list(world, request.read_joints, "step"))


def run_until(ctx: TimeContext, call: Call, request: rq.RunUntil) -> dict[str, Any] | None:
    target = request.sim_time
    world = ctx.world_for(request)
    dt = world.engine.timestep
    steps = (target - world.sim_time) / dt - 1e-9
    limit = ctx.limits.max_steps
    if steps > limit:
        raise InvalidArgumentError(
            f"run_until.sim_time {target:g} s is {steps:.3g} steps of {dt:g} s away; one "
            f"request takes at most {limit} steps (to sim time "
            f"{world.sim_time + limit * dt:g} s)", {"max_steps": limit})
    count = math.ceil(steps)
    if count <= 0:
        raise InvalidArgumentError(
            f"run_until.sim_time {target} is not after the current sim time "
            f"{world.sim_time}")
    read = _read_list(world, request.read, "run_until")
    _start_job(ctx, call, world, count, read, _rest_check(request.until_rest, read, dt),
               _read_joint_list(world, request.read_joints, "run_until"))
    return None


def reset(ctx: TimeContext, call: Call, request: rq.Reset) -> dict[str, Any]:
    scope = request.scope
    world = ctx.world_for(request)
    _cancel_job_on(ctx, world, "reset")
    world.reset(scope)
    if world is ctx.world:
        _after_reset(ctx)
    ctx.emit({"kind": "scene", "op": "reset", "scope": scope, "world": world.name,
               "step": world.step_index})
    return ctx.status().to_wire() if world is ctx.world else side_status(ctx, world).to_wire()


def load_world(ctx: TimeContext, call: Call, request: rq.LoadWorld) -> dict[str, Any]:
    """Replace the world with a fresh one on the named engine, in this process."""
    _live_only(ctx, request, "load_world")
    name = request.engine
    if ctx.engine_factory is None:
        raise OperationFailedError("this daemon cannot switch engines")
    engine = ctx.engine_factory(name)
    params = request.params
    if params is not None:
        try:
            engine.set_params(params)
        except Exception:
            engine.close()
            raise
    cancel_job(ctx, "world replaced")
    end_queued(ctx, ctx.world.name, "world replaced")
    old, ctx.world = ctx.world, World(engine, ctx.world.name, ctx.limits)
    old.engine.close()
    ctx.tune_switch_interval()
    _after_reset(ctx)
    ctx.set_state(SimState.STOPPED)
    ctx.emit({"kind": "scene", "op": "load_world", "engine": name, "world": ctx.world.name,
               "step": 0})
    return ctx.status().to_wire()


# -- helpers ------------------------------------------------------------------------
def _read_list(world: World, read: list[str] | None, where: str) -> list[str] | None:
    """The entities a step request wants read back when done; unknown names reject the
    request before any step is taken."""
    if read is None:
        return None
    names = check_names(read, f"{where}.read")
    world.require_known(names)
    return names


def _read_joint_list(world: World, read: list[str] | None, where: str
                     ) -> list[str] | None:
    """The joints a step request wants read back when done, checked before any step."""
    if read is None:
        return None
    names = check_names(read, f"{where}.read_joints")
    world.joints.require_scalar(names, f"{where}.read_joints")
    return names


def _start_job(ctx: TimeContext, call: Call, world: World, count: int,
               read: list[str] | None = None, rest: RestCheck | None = None,
               read_joints: list[str] | None = None) -> None:
    live = world is ctx.world
    if live and ctx.state == SimState.PLAYING:
        raise IncorrectStateError("cannot step while playing: pause first")
    require_reads_room(ctx.limits.max_reply_bytes, read, read_joints)
    world.require_valid()
    # Checked last: a request that waits is valid as the world stands now.
    if ctx.job is not None or ctx.step_queue.must_wait(call):
        raise StepBusyError("another step request is still running")
    if live and ctx.state == SimState.STOPPED:
        ctx.set_state(SimState.PAUSED)
    ctx.start_job(StepJob(call, count, count, read, rest, read_joints,
                           world=None if live else world))


def require_reads_room(limit: int, read: list[str] | None,
                       read_joints: list[str] | None) -> None:
    """Refuse, before its first step, a step request whose reads would make a reply over
    ``max_reply_bytes``: refused after its steps, it would have changed the world."""
    size = reads_size(read, read_joints)
    require_room(f"this step request's reply (the states of {len(read or ())} bodies and "
                 f"{len(read_joints or ())} joints)", size, limit,
                 "no step was taken; read fewer bodies, and get_states the rest in parts")


def client_gone(ctx: OpContext, client: str) -> None:
    """A client's liveliness token vanished, or its ZeroMQ connection closed: the step
    request it is waiting for ends now (its reply has nowhere to go), the world stays paused
    where it got to, and control it held is released (daemon/access/lease.py). The event names the
    client by its id, else by its connection."""
    job = ctx.job
    # Over ZeroMQ the step is tied to its connection alone, not to a token named like its id.
    if job is not None and client == (job.call.peer if job.call.peer is not None
                                      else job.call.client):
        cancel_job(ctx, "its client disappeared")
        ctx.emit({"kind": "job_abandoned", "client": job.call.client or client,
                   "steps_done": job.done,
                   "steps_asked": job.total, "step": ctx.world.step_index})
    dropped = ctx.step_queue.drop_client(client)  # no reply could reach it
    if dropped:
        ctx.emit({"kind": "steps_dropped", "client": dropped[0].client or client,
                   "count": len(dropped), "step": ctx.world.step_index})
    lease.client_gone(ctx, client)


def _cancel_job_on(ctx: TimeContext, world: World, reason: str) -> None:
    """Cancel the running step request if it steps this world, or predicts from it (a
    prediction is long work on the world's behalf: pause, stop and reset end it too)."""
    job = ctx.job
    if job is not None and world in ((job.world or ctx.world), job.source):
        cancel_job(ctx, reason)
    end_queued(ctx, world.name, reason)


def cancel_job(ctx: JobEnd, reason: str) -> None:
    job = ctx.end_job()
    if job is None:
        return
    job.release()
    ctx.replies.error(job.call, OperationFailedError(
        f"step request interrupted ({reason}) after {job.done} of {job.total} steps",
        {"steps_done": job.done}))


def end_queued(ctx: Jobs, world: str, reason: str) -> None:
    """Answer the step requests waiting to step ``world``: they will not run."""
    for call in ctx.step_queue.end_for(world, ctx.world.name):
        ctx.replies.error(call, OperationFailedError(
            f"step request interrupted ({reason}) before its first step: it was waiting "
            "for another step request", {"steps_done": 0}))


def _after_reset(ctx: TimeContext) -> None:
    ctx.refresh_clock()
    ctx.rtf_window.clear()
    ctx.pacer.anchor(time.monotonic(), ctx.world.sim_time, ctx.target_rtf)
