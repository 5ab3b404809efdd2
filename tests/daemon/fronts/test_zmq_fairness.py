"""A ZeroMQ client that floods the daemon and never reads its replies starves nobody
(issue 35, item 8): each connection's requests wait in a bounded queue of their own, taken
in turn with every other connection's and with Zenoh's. On both engines."""

from __future__ import annotations

import time
from collections.abc import Iterator

import msgpack
import pytest
import zmq
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon, plane, spheres
from galton.daemon.fronts.zmq import MAX_QUEUED_PER_CONNECTION

FLOOD = 1800
PROMPT_S = 3.0  # a status behind the flood took 9 s; behind one render, milliseconds
CAMERA = {"cameras": [{"eye": [2, 0, 1], "target": [0, 0, 0.5], "width": 320,
                       "height": 240}]}


def envelope(op: str, args: dict | None = None) -> bytes:
    return msgpack.packb({"v": 1, "op": op, "args": args or {}}, use_bin_type=True)


@pytest.fixture
def sockets(daemons: dict[str, EmbeddedDaemon], engine: str
            ) -> Iterator[tuple[zmq.Socket, zmq.Socket]]:
    """A flooding DEALER and a polite one on a fresh world of balls."""
    daemon = start_daemon(daemons, engine)
    with Client(daemon.instance, daemon.endpoint) as sim:
        sim.load_world(engine)
        sim.spawn(plane(), spheres([f"b{i}" for i in range(10)],
                                   [[0.2 * i, 0, 0.5] for i in range(10)], 0.05))
    context = zmq.Context()
    assert daemon.zmq_endpoint is not None
    flood, polite = context.socket(zmq.DEALER), context.socket(zmq.DEALER)
    for socket in (flood, polite):
        socket.connect(daemon.zmq_endpoint.removeprefix("zmq+"))
    try:
        yield flood, polite
    finally:
        context.destroy(linger=0)


def _round_trip(socket: zmq.Socket, op: str) -> float:
    started = time.monotonic()
    socket.send(envelope(op))
    assert socket.poll(int(20 * PROMPT_S * 1000)), f"no reply to {op}"
    assert msgpack.unpackb(socket.recv_multipart()[-1])["code"] == 0
    return time.monotonic() - started


def test_a_client_that_never_reads_starves_no_other(sockets: tuple[zmq.Socket, zmq.Socket]
                                                    ) -> None:
    flood, polite = sockets
    polite.send(envelope("render", CAMERA))  # the renderer made before the clock starts
    assert polite.poll(60_000)
    polite.recv_multipart()
    sent = 0
    for _ in range(FLOOD):
        try:
            flood.send(envelope("render", CAMERA), zmq.NOBLOCK)
        except zmq.Again:  # the daemon's queue for it is full: back-pressure on it alone
            break
        sent += 1
    assert sent > MAX_QUEUED_PER_CONNECTION
    waits = [_round_trip(polite, "status") for _ in range(4)]
    assert max(waits) < PROMPT_S, waits
    flood.close(linger=0)
    assert _round_trip(polite, "status") < PROMPT_S
