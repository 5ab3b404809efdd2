"""Status and telemetry. A status request is answered from one reading of the loop's
status values, without waiting for the physics thread (the one ``fast`` operation of
protocol/operations.py).

A controller polling a paused or idle daemon asks the same thing of the same values
again and again, so the last reply's bytes are kept with the request and reading they
answer: a repeated poll costs one comparison, not a decode and an encode (about 30 µs of a
0.3 ms round trip, docs/PERFORMANCE.md).
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING, Any

import msgpack

from galton.daemon.core.calls import TELEMETRY, Call
from galton.daemon.core.clock import WorldClock
from galton.protocol import (
    NotFoundError,
    OperationFailedError,
    RemoteError,
    Reply,
    ResultCode,
    SimState,
    SimStatus,
    Telemetry,
    decode_request,
    encode_reply,
    error_reply,
)
from galton.protocol.errors import brief, did_you_mean
from galton.protocol.operations import operation

if TYPE_CHECKING:
    from galton.daemon.core.loop import SimLoop
    from galton.daemon.world.world import World

log = logging.getLogger("galton.daemon")


def read_status(loop: SimLoop) -> tuple[Any, ...]:
    """Everything a status reply says, read at once: equal readings give equal replies."""
    job = loop.job
    return (loop.clock, loop.state, loop.target_rtf, loop.rtf, loop.world,
            loop.lease.controller, job is not None)


def status_from(loop: SimLoop, taken: tuple[Any, ...]) -> SimStatus:
    clock: WorldClock
    clock, state, target_rtf, rtf, world, controller, stepping = taken
    return SimStatus(
        state=state, step=clock.step, sim_time=clock.sim_time, timestep=clock.timestep,
        target_rtf=target_rtf, rtf=rtf, entity_count=clock.entity_count,
        engine=world.engine.name, instance=loop.instance, world=world.name,
        faulted=clock.faulted, controller=controller, stepping=stepping)


def answer_status(loop: SimLoop, call: Call) -> None:
    """Answer one status request on the caller's thread; never raises."""
    taken = read_status(loop)
    cached = loop.status_reply
    if cached is not None and cached[0] == call.payload and cached[1] == taken:
        loop.send(call, cached[2])
        return
    status = status_from(loop, taken)
    try:
        request = decode_request(call.payload, call.op, loop.decode_limits)
        operation(request.op).decode(request.args)
        named = request.args.get("world")
        if named is not None and named != status.world:
            if not isinstance(named, str) or named not in loop.side:
                raise NotFoundError(f"no world named {brief(named)}"
                                    f"{did_you_mean(str(named)[:64], world_names(loop))}; "
                                    "list_worlds lists them")
            loop.submit(call)  # a side world's status: the physics thread answers it
            return
        reply = Reply(ResultCode.OK, result=status.to_wire(), step=status.step,
                      sim_time=status.sim_time)
    except Exception as exc:  # on the transport's thread: whatever happens, one typed reply
        loop.send(call, _error_data(exc, status))
        return
    data = encode_reply(reply)
    loop.status_reply = (call.payload, taken, data)
    loop.send(call, data)


def world_names(loop: SimLoop) -> list[str]:
    """The live and side worlds' names, read on the transport's thread while the physics
    thread may add or remove one: copied in one C call (no Python code runs between its
    items), and a copy that meets a change anyway suggests the live world alone."""
    try:
        return [loop.world.name, *tuple(loop.side)]
    except RuntimeError:  # the dict changed size while it was copied
        return [loop.world.name]


def _error_data(exc: Exception, status: SimStatus) -> bytes:
    """The error reply's bytes. Apart so that no local of ``answer_status`` holds the
    exception: its traceback holds that frame, and the frame the call, so a local would make
    a cycle that kept the request's payload until a full collection (issue 46: each refused
    50 MB status left the RSS 48 MiB up)."""
    error = exc if isinstance(exc, RemoteError) else OperationFailedError(
        f"{type(exc).__name__}: {brief(str(exc))}")
    return encode_reply(error_reply(error, status.step, status.sim_time))


def side_state(world: World) -> SimState:
    """A side world never plays: stopped until its first step, paused after."""
    return SimState.STOPPED if world.step_index == 0 else SimState.PAUSED


def publish_telemetry(loop: SimLoop, now: float) -> None:
    """Publish one telemetry sample per world, the live one first (after checking it is
    still finite); a side world's sample reads as its ``status`` does (never playing)."""
    if not loop.world.faulted:
        loop.stepping.verify()
    cpu, rss, peak = loop.monitor.sample()
    rtf = loop.rtf = loop.rtf_window.add(now, loop.world.sim_time)
    wall = time.time()
    samples = [(loop.world, loop.state, rtf, loop.target_rtf)]
    samples.extend((world, side_state(world), 0.0, 0.0) for world in loop.side.values())
    for world, state, world_rtf, target_rtf in samples:
        loop.telemetry_seq += 1
        sample = Telemetry(
            seq=loop.telemetry_seq, instance=loop.instance, engine=world.engine.name,
            state=state, step=world.step_index, sim_time=world.sim_time, wall_time=wall,
            rtf=world_rtf, target_rtf=target_rtf, timestep=world.engine.timestep,
            entity_count=len(world.entities), cpu_percent=cpu, rss_bytes=rss,
            peak_rss_bytes=peak, world=world.name)
        try:
            loop.wiring.publish(TELEMETRY, msgpack.packb(sample.to_wire()))
        except Exception:
            log.exception("could not publish telemetry")
