"""Many clients asking for one step each share the stepping (issue 35, item 10): a step
asked while another runs waits for it (daemon/core/step_queue.py: none of twenty is
refused), and the loop goes back to the physics as soon as a step starts, so the steps a
crowd gets done stay near what one client alone gets (they fell from 1,432 to 33 steps/s).
Over ZeroMQ, where one thread can keep twenty connections busy; on both engines."""

from __future__ import annotations

import time

import msgpack
import pytest
import zmq
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon

CROWD = 20
WINDOW_S = 2.0
SHARE = 0.4  # the crowd's steps per second, at least this share of one client's


def envelope(op: str, args: dict | None = None) -> bytes:
    return msgpack.packb({"v": 1, "op": op, "args": args or {}}, use_bin_type=True)


def steps_per_second(endpoint: str, clients: int, seconds: float) -> tuple[float, int]:
    """Steps accepted per second while ``clients`` DEALERs each keep one step(1) in flight;
    and how many were refused."""
    context = zmq.Context()
    try:
        poller = zmq.Poller()
        sockets = [context.socket(zmq.DEALER) for _ in range(clients)]
        for socket in sockets:
            socket.connect(endpoint)
            poller.register(socket, zmq.POLLIN)
            socket.send(envelope("step", {"count": 1}))
        done = refused = 0
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            for socket, _ in poller.poll(1000):
                code = msgpack.unpackb(socket.recv_multipart()[-1])["code"]
                done += code == 0
                refused += code != 0
                socket.send(envelope("step", {"count": 1}))
        return done / seconds, refused
    finally:
        context.destroy(linger=0)


@pytest.mark.slow  # a throughput ratio: on demand, on a quiet machine (-m slow)
def test_a_crowd_of_single_steps_keeps_the_stepping_going(
        daemons: dict[str, EmbeddedDaemon], engine: str) -> None:
    daemon = start_daemon(daemons, engine)
    with Client(daemon.instance, daemon.endpoint) as sim:
        sim.load_world(engine)
    assert daemon.zmq_endpoint is not None
    endpoint = daemon.zmq_endpoint.removeprefix("zmq+")
    alone, _ = steps_per_second(endpoint, 1, WINDOW_S)
    crowd, refused = steps_per_second(endpoint, CROWD, WINDOW_S)
    assert refused == 0  # twenty waiting step requests are within the queue's bound
    assert crowd >= SHARE * alone, (crowd, alone)
