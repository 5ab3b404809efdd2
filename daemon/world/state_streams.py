"""State streams: the poses of all (or named) entities of a world, published at the rate
a client asked (``stream_states``), beside telemetry, on every front that carries them.

A stream belongs to the client that opened it (its liveliness token over Zenoh, its
connection over ZeroMQ) and ends when that client goes, on ``close_stream``, or when the
side world it watches is deleted. Besides the fronts' word that a client went, the owners
are asked of the fronts every LIVENESS_PERIOD_S (``client_alive``): a ZeroMQ connection
silent for ``zmq_silence_s`` counts as gone, though a stopped process keeps it open.

Samples are built on the physics thread between chunks of steps and handed to publishers
that drop rather than wait (Zenoh's ``DROP`` congestion control, a non-blocking ZeroMQ
send): a slow subscriber never slows the world.

A sample is cheap for the physics thread (docs/PERFORMANCE.md, "State streams"): while its
world holds the same entities a stream reuses its names, packed once, and the engine's pose
reader of them (``Engine.pose_reader``); streams of the same world and names due together
share one read; the Zenoh front puts samples on a thread of its own
(daemon/fronts/stream_sender.py).
"""

from __future__ import annotations

import logging
import math
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import msgpack
import numpy as np

from galton.daemon.core.calls import Call, Publish
from galton.daemon.core.context import StreamContext
from galton.daemon.world.world import World, canonical_quaternions
from galton.protocol import InvalidArgumentError, Keys, NotFoundError, ResourceLimitError
from galton.protocol import requests as rq
from galton.protocol.arrays import pack_f64
from galton.protocol.errors import brief
from galton.protocol.keys import STREAMS_CHUNK

MAX_STREAMS = 32  # open streams in one daemon, all clients together ("max_streams")
# Open streams one client may hold ("max_streams_per_client"): the pool is shared, so no
# client can hold all of it (issue 46).
MAX_STREAMS_PER_CLIENT = 8
NO_OWNER = ("a state stream belongs to a client, and ends when it goes: the request needs "
            "a 'client' id in its envelope (the SDK sends one)")
CLIENT_GONE = "its client went"  # the ``ended`` of a stream whose client went
LIVENESS_PERIOD_S = 0.25  # how often the streams' owners are asked of the fronts

log = logging.getLogger("galton.daemon")


@dataclass
class Reading:
    """What a stream's samples reuse while its world holds the same entities: the names
    present, packed once, and the engine's reader of their poses."""

    world: World
    layout: int
    names: list[str]
    packed_names: bytes
    read: Callable[[], np.ndarray]


@dataclass
class StateStream:
    """One subscription's parameters and its clock."""

    stream_id: str
    owner: str
    world: str | None  # None: the live world, whichever it is
    names: tuple[str, ...] | None  # None: every entity
    period: float
    next_due: float
    seq: int = 0
    reading: Reading | None = None

    @property
    def topic(self) -> str:
        return f"{STREAMS_CHUNK}/{self.stream_id}"


class StateStreams:
    """Every open stream of one daemon; used on the physics thread only."""

    def __init__(self, publish: Publish) -> None:
        # Every front's publish, on the physics thread: each front decides whether and how
        # it carries a sample (Zenoh hands it to a thread of its own, ZeroMQ sends it).
        self.publish = publish
        self.streams: dict[str, StateStream] = {}
        self.next_due = math.inf
        self.next_liveness = 0.0

    def open(self, ctx: StreamContext, call: Call, request: rq.StreamStates) -> dict[str, Any]:
        """Open a stream for the request's client; its first sample is due at once."""
        rate = request.rate
        names = request.names
        world = ctx.world_for(request)
        if names is not None:
            world.require_known(names)
        owner = _owner(ctx, call)
        self._require_room(owner)
        named = request.world
        stream = StateStream(secrets.token_hex(8), owner,
                             named if isinstance(named, str) and world is not ctx.world
                             else None,
                             tuple(names) if names is not None else None, 1.0 / rate,
                             time.monotonic())
        self.streams[stream.stream_id] = stream
        self.next_due = min(self.next_due, stream.next_due)
        return {"stream": stream.stream_id, "key": f"{Keys(ctx.instance).prefix}/{stream.topic}",
                "topic": stream.topic, "rate": rate, "world": world.name,
                "silence_s": ctx.limits.zmq_silence_s if call.peer is not None else None}

    def _require_room(self, owner: str) -> None:
        """RESOURCE_LIMIT past the pool, or past this client's share of it (docs/protocol.md,
        "Limits": ``details.limit`` names the limit, ``details.max`` gives its value)."""
        if len(self.streams) >= MAX_STREAMS:
            raise ResourceLimitError(
                f"stream_states: {MAX_STREAMS} state streams are open already (each client's "
                "end when it goes): close one with close_stream",
                {"limit": "max_streams", "max": MAX_STREAMS})
        held = sum(1 for s in self.streams.values() if s.owner == owner)
        if held >= MAX_STREAMS_PER_CLIENT:
            raise ResourceLimitError(
                f"stream_states: this client holds {held} state streams, at most "
                f"{MAX_STREAMS_PER_CLIENT} a client (the pool of {MAX_STREAMS} is shared): "
                "close one with close_stream",
                {"limit": "max_streams_per_client", "max": MAX_STREAMS_PER_CLIENT})

    def close(self, call: Call, request: rq.CloseStream) -> dict[str, Any]:
        """Close a stream; a client may close only its own."""
        stream_id = request.stream
        stream = self.streams.get(stream_id)
        if stream is None or stream.owner != _caller(call):
            raise NotFoundError(f"close_stream: no stream {brief(stream_id)} of this client is "
                                f"open (it ends by itself when its client goes)")
        self._end(stream)
        return {"stream": stream_id, "closed": True}

    def owner_gone(self, owner: str) -> None:
        """Its client went: its streams end, each with a last sample that says so (another
        subscriber of the stream's key learns it ended, not that it went quiet)."""
        for stream in [s for s in self.streams.values() if s.owner == owner]:
            self._end(stream, CLIENT_GONE)

    def end_gone_owners(self, ctx: StreamContext) -> None:
        """End the streams of every owner a front knows to be gone (not those no front can
        tell of): the fronts' word comes as a task, but a silent ZeroMQ connection is found
        only by asking."""
        if ctx.client_alive is None:
            return
        for owner in {stream.owner for stream in self.streams.values()}:
            if ctx.client_alive(owner) is False:
                log.warning("the state streams of %s end: its client has gone (or, over "
                            "ZeroMQ, sent nothing for %g s)", owner, ctx.limits.zmq_silence_s)
                self.owner_gone(owner)

    def publish_due(self, ctx: StreamContext, now: float) -> None:
        """Publish a sample of every stream that is due, and schedule each one's next;
        first, now and then, end those of owners gone (streams are due at least 1 Hz)."""
        if now >= self.next_liveness:
            self.next_liveness = now + LIVENESS_PERIOD_S
            self.end_gone_owners(ctx)
        shared: dict[tuple[int, int, tuple[str, ...] | None], bytes] = {}
        for stream in list(self.streams.values()):
            if now < stream.next_due:
                continue
            stream.next_due = max(stream.next_due + stream.period, now)
            self._sample(ctx, stream, shared)
        self._reschedule()

    def _sample(self, ctx: StreamContext, stream: StateStream,
                shared: dict[tuple[int, int, tuple[str, ...] | None], bytes]) -> None:
        """One sample; ``shared`` holds the poses this round already read, by world and
        names, so that streams of the same world read it once."""
        world = ctx.world if stream.world is None else ctx.side.get(stream.world)
        if world is None:
            self._end(stream, f"world {stream.world!r} was deleted")
            return
        if world.faulted:
            return  # a diverged state is never published (as telemetry)
        reading = _reading(stream, world)
        key = (id(world), world.layout, stream.names)
        poses = shared.get(key)
        if poses is None:
            poses = shared[key] = _pose_bytes(world, reading)
        stream.seq += 1
        live = world is ctx.world
        header = {"stream": stream.stream_id, "seq": stream.seq, "world": world.name,
                  "step": world.step_index, "sim_time": world.sim_time,
                  "state": ctx.state.value if live else "paused",
                  "rtf": ctx.rtf if live else 0.0, "poses": poses}
        self._send_bytes(stream, _pack_sample(header, reading.packed_names))

    def _end(self, stream: StateStream, reason: str = "") -> None:
        self.streams.pop(stream.stream_id, None)
        if reason:
            self._send(stream, {"stream": stream.stream_id, "seq": stream.seq + 1,
                                "ended": reason})
        self._reschedule()

    def _send(self, stream: StateStream, sample: dict[str, Any]) -> None:
        self._send_bytes(stream, msgpack.packb(sample))

    def _send_bytes(self, stream: StateStream, data: bytes) -> None:
        self.publish(stream.topic, data)

    def _reschedule(self) -> None:
        self.next_due = min((s.next_due for s in self.streams.values()), default=math.inf)


def _reading(stream: StateStream, world: World) -> Reading:
    """The stream's reading of this world, made anew when the world's entities changed."""
    reading = stream.reading
    if reading is None or reading.world is not world or reading.layout != world.layout:
        names = _present(world, stream.names)
        reading = stream.reading = Reading(world, world.layout, names, msgpack.packb(names),
                                           world.engine.pose_reader(names))
    return reading


def _pose_bytes(world: World, reading: Reading) -> bytes:
    """The packed poses of the reading's names, from a checked state."""
    if not reading.names:
        return b""
    poses = reading.read()
    if not _plausible(world, poses):
        world.verify()  # the full check: it faults the world if the state diverged
    return pack_f64(canonical_quaternions(poses))


def _plausible(world: World, poses: np.ndarray) -> bool:
    """Whether poses may leave the daemon without the full check of World.verify (every
    body's position and speed), which the loop runs every VERIFY_PERIOD_S while stepping:
    the state since it is checked here as far as the sample carries it, finite positions
    within max_position and finite quaternions."""
    if world.verified_step == world.step_index and not world.teleported:
        return not world.faulted
    return bool(np.isfinite(poses).all()) and \
        float(np.abs(poses[:, :3]).max(initial=0.0)) <= world.limits.max_position


def _pack_sample(header: dict[str, Any], packed_names: bytes) -> bytes:
    """msgpack of the header's map with a "names" entry whose value is packed already."""
    packer = msgpack.Packer()
    parts = [packer.pack_map_header(len(header) + 1)]
    for key, value in header.items():
        parts += [packer.pack(key), packer.pack(value)]
    parts += [packer.pack("names"), packed_names]
    return b"".join(parts)


def _present(world: World, names: tuple[str, ...] | None) -> list[str]:
    """The stream's entities still in the world (all of them when it named none)."""
    if names is None:
        return list(world.entities)
    return [name for name in names if name in world.entities]


def _caller(call: Call) -> str | None:
    """Who a request comes from: its connection over ZeroMQ, else its client id."""
    return call.peer if call.peer is not None else call.client


def _owner(ctx: StreamContext, call: Call) -> str:
    owner = _caller(call)
    if owner is None:
        raise InvalidArgumentError(NO_OWNER)
    if call.peer is None and ctx.client_alive is not None and not ctx.client_alive(owner):
        # A made-up id would keep its stream for ever: nothing would say it has gone.
        raise InvalidArgumentError(
            f"client {owner!r} holds no liveliness token galton/_clients/{owner}: a state "
            "stream ends when that token goes (the SDK declares it)")
    return owner


def stream_states(ctx: StreamContext, call: Call, request: rq.StreamStates) -> dict[str, Any]:
    """The ``stream_states`` operation (docs/protocol.md, "State streams")."""
    return ctx.streams.open(ctx, call, request)


def close_stream(ctx: StreamContext, call: Call, request: rq.CloseStream) -> dict[str, Any]:
    """The ``close_stream`` operation."""
    return ctx.streams.close(call, request)
