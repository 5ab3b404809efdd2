"""Step requests sent while another runs wait for it (issue 35, item 10): in arrival order,
up to MAX_QUEUED_STEPS (beyond: RESOURCE_LIMIT); a client gone drops its own; pause, stop
and reset end them with OPERATION_FAILED before their first step. Raw ZeroMQ DEALERs, one
per client, on MuJoCo (the queue is the core's, the same for every engine and front)."""

from __future__ import annotations

import queue
from collections.abc import Iterator
from typing import Any

import msgpack
import pytest
import zmq
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon, plane, spheres
from galton.daemon.core.step_queue import MAX_QUEUED_PER_CLIENT, MAX_QUEUED_STEPS
from galton.protocol import ResourceLimitError, ResultCode

LONG = 10**8  # steps of a request that runs until it is ended
WAIT_MS = 30_000


def envelope(op: str, args: dict | None = None) -> bytes:
    return msgpack.packb({"v": 1, "op": op, "args": args or {}}, use_bin_type=True)


def reply(socket: zmq.Socket) -> dict[str, Any]:
    assert socket.poll(WAIT_MS), "no reply"
    answer: dict[str, Any] = msgpack.unpackb(socket.recv_multipart()[-1])
    return answer


class Crowd:
    """DEALERs on one daemon's ZeroMQ front, each a client of its own."""

    def __init__(self, endpoint: str, sim: Client) -> None:
        self.endpoint = endpoint
        self.sim = sim  # over Zenoh: its events
        self.context = zmq.Context()
        self.sockets: list[zmq.Socket] = []

    def client(self) -> zmq.Socket:
        socket = self.context.socket(zmq.DEALER)
        socket.connect(self.endpoint)
        self.sockets.append(socket)
        return socket

    def close(self) -> None:
        for socket in self.sockets:
            socket.close(linger=0)
        self.context.term()

    def send(self, socket: zmq.Socket, op: str, args: dict | None = None) -> None:
        """Send, and make sure the daemon has taken it: a status sent after it on the same
        connection is answered after it is taken (each connection's requests in order)."""
        socket.send(envelope(op, args))
        socket.send(envelope("status"))
        assert reply(socket)["code"] == 0


@pytest.fixture
def crowd(daemons: dict[str, EmbeddedDaemon]) -> Iterator[Crowd]:
    daemon = start_daemon(daemons, "mujoco")
    assert daemon.zmq_endpoint is not None
    with Client(daemon.instance, daemon.endpoint) as sim:
        sim.load_world("mujoco")
        sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
        made = Crowd(daemon.zmq_endpoint.removeprefix("zmq+"), sim)
        try:
            yield made
        finally:
            made.close()


def test_waiting_steps_run_in_arrival_order_and_a_client_gone_loses_its_own(
        crowd: Crowd) -> None:
    runner, first, gone, last = (crowd.client() for _ in range(4))
    crowd.send(runner, "step", {"count": LONG})
    for socket in (first, gone, last):
        crowd.send(socket, "step", {"count": 1})
    events: queue.Queue[dict[str, Any]] = queue.Queue()
    with crowd.sim.on_event(events.put):
        # A round trip after the subscriber's declaration, on the same Zenoh link: the
        # daemon has taken the declaration before it answers, so no event is missed.
        crowd.sim.status()
        gone.close(linger=0)  # its waiting step goes with it
        event = events.get(timeout=WAIT_MS / 1000)
        while event["kind"] != "steps_dropped":
            event = events.get(timeout=WAIT_MS / 1000)
    assert event["count"] == 1
    runner.close(linger=0)  # its running step ends: the queue moves on
    one, two = reply(first), reply(last)
    assert (one["code"], two["code"]) == (0, 0)
    assert one["result"]["steps"] == two["result"]["steps"] == 1
    assert two["step"] == one["step"] + 1  # in arrival order, and gone's step never ran


@pytest.mark.parametrize("ender", ["pause", "stop", "reset"])
def test_pause_stop_and_reset_end_the_waiting_steps(crowd: Crowd, ender: str) -> None:
    runner, waiting, boss = (crowd.client() for _ in range(3))
    crowd.send(runner, "step", {"count": LONG})
    crowd.send(waiting, "step", {"count": 1, "read": ["ball"]})
    boss.send(envelope(ender))
    assert reply(boss)["code"] == 0
    assert reply(runner)["code"] == ResultCode.OPERATION_FAILED
    ended = reply(waiting)
    assert ended["code"] == ResultCode.OPERATION_FAILED
    assert ended["details"]["steps_done"] == 0 and "before its first step" in ended["message"]
    boss.send(envelope("step", {"count": 1}))
    assert reply(boss)["code"] == 0  # the slot is free again


def collect(sockets: list[zmq.Socket], count: int) -> list[dict[str, Any]]:
    """The next ``count`` replies to any of ``sockets``."""
    poller = zmq.Poller()
    for socket in sockets:
        poller.register(socket, zmq.POLLIN)
    got: list[dict[str, Any]] = []
    while len(got) < count:
        ready = poller.poll(WAIT_MS)
        assert ready, f"{len(got)} of {count} replies"
        got += [msgpack.unpackb(socket.recv_multipart()[-1]) for socket, _ in ready]
    return got


def test_steps_past_a_clients_share_are_refused_at_once(crowd: Crowd) -> None:
    """Each client has at most MAX_QUEUED_PER_CLIENT steps waiting (issue 46: one client's
    flood once filled the queue for all)."""
    runner, boss = crowd.client(), crowd.client()
    crowd.send(runner, "step", {"count": LONG})
    senders = [crowd.client() for _ in range(4)]
    each = MAX_QUEUED_PER_CLIENT + 5
    for socket in senders:
        for _ in range(each):
            socket.send(envelope("step", {"count": 1}))
    waiting = len(senders) * MAX_QUEUED_PER_CLIENT
    refused = collect(senders, len(senders) * each - waiting)  # the rest wait
    assert {r["code"] for r in refused} == {ResultCode.RESOURCE_LIMIT}
    assert refused[0]["details"] == {"limit": "queued_steps_per_client",
                                     "max": MAX_QUEUED_PER_CLIENT}
    boss.send(envelope("pause"))
    assert reply(boss)["code"] == 0
    ended = collect(senders, waiting)
    assert {r["code"] for r in ended} == {ResultCode.OPERATION_FAILED}


def test_past_the_shared_bound_only_a_client_with_none_waiting_gets_in(crowd: Crowd) -> None:
    runner, boss, polite = crowd.client(), crowd.client(), crowd.client()
    crowd.send(runner, "step", {"count": LONG})
    senders = [crowd.client() for _ in range(MAX_QUEUED_STEPS // MAX_QUEUED_PER_CLIENT)]
    for socket in senders:
        for _ in range(MAX_QUEUED_PER_CLIENT):
            crowd.send(socket, "step", {"count": 1})  # 64 waiting in all
    crowd.send(polite, "step", {"count": 1})  # still taken: it has none waiting
    polite.send(envelope("step", {"count": 1}))  # its second is past the shared bound
    second = reply(polite)
    assert second["code"] == ResultCode.RESOURCE_LIMIT
    assert second["details"] == {"limit": "queued_steps", "max": MAX_QUEUED_STEPS}
    boss.send(envelope("pause"))
    assert reply(boss)["code"] == 0
    assert reply(polite)["code"] == ResultCode.OPERATION_FAILED  # its first was waiting
    collect(senders, MAX_QUEUED_STEPS)


def test_a_polite_clients_steps_are_answered_under_twenty_hammering_clients(
        crowd: Crowd) -> None:
    """Issue 46: with twenty DEALERs each keeping 64 step(1) in flight, a polite client's
    step(1) was refused 422 times of 596; now it waits its turn, and is answered."""
    hammers = [crowd.client() for _ in range(20)]
    in_flight = dict.fromkeys(hammers, 0)
    poller = zmq.Poller()
    for socket in hammers:
        poller.register(socket, zmq.POLLIN)
    polite = Client(crowd.sim.instance, f"zmq+{crowd.endpoint}", timeout=30.0)
    answered = 0
    try:
        for _ in range(10):
            for socket in hammers:  # keep every hammer's pipeline full
                while in_flight[socket] < 64:
                    socket.send(envelope("step", {"count": 1}))
                    in_flight[socket] += 1
            for socket, _ in poller.poll(0):
                while socket.poll(0):
                    socket.recv_multipart()
                    in_flight[socket] -= 1
            try:
                polite.step(1)
                answered += 1
            except ResourceLimitError:
                pass
    finally:
        polite.close()
    assert answered >= 9
