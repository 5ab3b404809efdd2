"""Status and telemetry: the ``StatusBoard`` of one loop. A status request is answered from
one reading of the loop's status values, without waiting for the physics thread (the one
``fast`` operation of protocol/operations.py); telemetry is published from the physics
thread at the wiring's rate, one sample per world.

A controller polling a paused or idle daemon asks the same thing of the same values
again and again, so the last reply's bytes are kept with the request and reading they
answer: a repeated poll costs one comparison, not a decode and an encode (about 30 µs of a
0.3 ms round trip, docs/PERFORMANCE.md).
"""

from __future__ import annotations

import logging
import math
import time
from typing import TYPE_CHECKING, Any, Protocol

import msgpack

from galton.daemon.core.calls import TELEMETRY, Call, Publish
from galton.daemon.core.clock import STOPPED_AT_ZERO, WorldClock
from galton.daemon.core.monitor import ProcessMonitor
from galton.daemon.core.replies import send
from galton.protocol import (
    DecodeLimits,
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
    from galton.daemon.access.lease import Lease
    from galton.daemon.core.calls import StepJob
    from galton.daemon.world.world import World

log = logging.getLogger("galton.daemon")


class Watched(Protocol):
    """What status and telemetry read of the loop (a status request: on any thread, each
    value read once; telemetry: on the physics thread)."""

    world: World
    side: dict[str, World]
    state: SimState
    target_rtf: float
    rtf: float
    job: StepJob | None
    lease: Lease

    @property
    def instance(self) -> str: ...


class StatusBoard:
    """The clock other threads read, the last status reply, and telemetry's sequence,
    process monitor and schedule."""

    def __init__(self, loop: Watched, publish: Publish, telemetry_rate_hz: float,
                 decode_limits: DecodeLimits) -> None:
        self.loop = loop
        self.publish = publish
        self.decode_limits = decode_limits
        self.clock: WorldClock = STOPPED_AT_ZERO  # swapped in whole by refresh()
        # The last status reply with the request and status reading it answered.
        self._last_reply: tuple[bytes, tuple[Any, ...], bytes] | None = None
        self.telemetry_period = 1.0 / telemetry_rate_hz if telemetry_rate_hz > 0 else math.inf
        self.next_telemetry = time.monotonic()
        self._telemetry_seq = 0
        self._monitor = ProcessMonitor()

    def refresh(self) -> None:
        """Take the live world's clock now (physics thread), as one value swapped in whole."""
        self.clock = WorldClock.of(self.loop.world)

    def _read(self) -> tuple[Any, ...]:
        """Everything a status reply says, read at once: equal readings give equal replies."""
        loop = self.loop
        return (self.clock, loop.state, loop.target_rtf, loop.rtf, loop.world,
                loop.lease.controller, loop.job is not None)

    def status(self) -> SimStatus:
        """Safe to call from any thread: reads only values swapped atomically."""
        return self._status_from(self._read())

    def _status_from(self, taken: tuple[Any, ...]) -> SimStatus:
        clock: WorldClock
        clock, state, target_rtf, rtf, world, controller, stepping = taken
        return SimStatus(
            state=state, step=clock.step, sim_time=clock.sim_time, timestep=clock.timestep,
            target_rtf=target_rtf, rtf=rtf, entity_count=clock.entity_count,
            engine=world.engine.name, instance=self.loop.instance, world=world.name,
            faulted=clock.faulted, controller=controller, stepping=stepping)

    def answer(self, call: Call) -> bool:
        """Answer one status request on the caller's thread; never raises. False: it names
        a side world, whose status the physics thread answers (the caller hands it over)."""
        taken = self._read()
        cached = self._last_reply
        if cached is not None and cached[0] == call.payload and cached[1] == taken:
            send(call, cached[2])
            return True
        status = self._status_from(taken)
        try:
            request = decode_request(call.payload, call.op, self.decode_limits)
            operation(request.op).decode(request.args)
            named = request.args.get("world")
            if named is not None and named != status.world:
                # On the transport's thread the physics thread may be adding or removing
                # a side world: one membership test, and the names copied in one C call.
                if not isinstance(named, str) or named not in self.loop.side:
                    raise NotFoundError(f"no world named {brief(named)}"
                                        f"{did_you_mean(str(named)[:64], world_names(self.loop))}"
                                        "; list_worlds lists them")
                return False
            reply = Reply(ResultCode.OK, result=status.to_wire(), step=status.step,
                          sim_time=status.sim_time)
        except Exception as exc:  # on the transport's thread: whatever happens, one reply
            send(call, _error_data(exc, status))
            return True
        data = encode_reply(reply)
        self._last_reply = (call.payload, taken, data)
        send(call, data)
        return True

    def telemetry_due(self, now: float) -> bool:
        """Whether a telemetry sample is due; if so, the next one is scheduled."""
        if now < self.next_telemetry:
            return False
        self.next_telemetry = max(self.next_telemetry + self.telemetry_period, now)
        return True

    def publish_telemetry(self) -> None:
        """Publish one telemetry sample per world, the live one first; a side world's
        sample reads as its ``status`` does (never playing)."""
        loop = self.loop
        cpu, rss, peak = self._monitor.sample()
        wall = time.time()
        samples = [(loop.world, loop.state, loop.rtf, loop.target_rtf)]
        samples.extend((world, side_state(world), 0.0, 0.0) for world in loop.side.values())
        for world, state, world_rtf, target_rtf in samples:
            self._telemetry_seq += 1
            sample = Telemetry(
                seq=self._telemetry_seq, instance=loop.instance, engine=world.engine.name,
                state=state, step=world.step_index, sim_time=world.sim_time, wall_time=wall,
                rtf=world_rtf, target_rtf=target_rtf, timestep=world.engine.timestep,
                entity_count=len(world.entities), cpu_percent=cpu, rss_bytes=rss,
                peak_rss_bytes=peak, world=world.name)
            try:
                self.publish(TELEMETRY, msgpack.packb(sample.to_wire()))
            except Exception:
                log.exception("could not publish telemetry")


def world_names(loop: Watched) -> list[str]:
    """The live and side worlds' names, read on the transport's thread while the physics
    thread may add or remove one: copied in one C call (no Python code runs between its
    items), and a copy that meets a change anyway suggests the live world alone."""
    try:
        return [loop.world.name, *tuple(loop.side)]
    except RuntimeError:  # the dict changed size while it was copied
        return [loop.world.name]


def _error_data(exc: Exception, status: SimStatus) -> bytes:
    """The error reply's bytes. Apart so that no local of ``StatusBoard.answer`` holds the
    exception: its traceback holds that frame, and the frame the call, so a local would make
    a cycle that kept the request's payload until a full collection (issue 46: each refused
    50 MB status left the RSS 48 MiB up)."""
    error = exc if isinstance(exc, RemoteError) else OperationFailedError(
        f"{type(exc).__name__}: {brief(str(exc))}")
    return encode_reply(error_reply(error, status.step, status.sim_time))


def side_state(world: World) -> SimState:
    """A side world never plays: stopped until its first step, paused after."""
    return SimState.STOPPED if world.step_index == 0 else SimState.PAUSED
