"""A ZeroMQ client's state streams end when it stops talking, not only when its socket
closes (issue 46): a stopped process keeps its connection open, and ZMTP heartbeats abort
libzmq 4.3.5 under load, so the daemon counts a connection silent for ``zmq_silence_s`` as
gone, and the SDK keeps its streams' connection heard (docs/protocol.md, "ZeroMQ")."""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import msgpack
import numpy as np
import pytest
import zmq

from galton.client import Client, EmbeddedDaemon
from galton.daemon.fronts.zmq import ZmqFront, telemetry_endpoint
from galton.protocol import ResourceLimitError, pack_f64
from galton.protocol.keys import STREAMS_CHUNK

SILENCE_S = 1.5  # the test daemon's zmq_silence_s: a tenth of the default
DEADLINE_S = 30.0  # what a wait may take on a loaded machine before the test fails
MAX_STREAMS, PER_CLIENT = 32, 8


@pytest.fixture(scope="module")
def daemon() -> Iterator[EmbeddedDaemon]:
    started = EmbeddedDaemon("mujoco", instance="zmq-keepalive", telemetry_rate=20.0,
                             zmq=True, extra_args=["--limit", f"zmq_silence_s={SILENCE_S}"])
    started.start()
    try:
        yield started
    finally:
        started.stop()


def control(daemon: EmbeddedDaemon) -> str:
    assert daemon.zmq_endpoint is not None
    return daemon.zmq_endpoint.removeprefix("zmq+")


def call(socket: zmq.Socket, op: str, args: dict | None = None) -> dict:
    socket.send(msgpack.packb({"v": 1, "op": op, "args": args or {}}))
    assert socket.poll(int(DEADLINE_S * 1000)), f"{op}: no reply"
    return msgpack.unpackb(socket.recv())  # type: ignore[no-any-return]


class Watcher:
    """A SUB socket on the daemon's telemetry endpoint that collects the streams' ``ended``
    samples, ready (greeted) before any stream opens."""

    def __init__(self, context: zmq.Context, daemon: EmbeddedDaemon) -> None:
        self.socket = context.socket(zmq.SUB)
        self.socket.connect(telemetry_endpoint(control(daemon)))
        prefix = f"galton/{daemon.instance}/"
        self.socket.subscribe(f"{prefix}hello")
        self.socket.subscribe(f"{prefix}{STREAMS_CHUNK}/")
        self.ended: dict[str, str] = {}
        self.live: set[str] = set()  # streams a sample came from that was no ending
        deadline = time.monotonic() + DEADLINE_S
        while not self._take(deadline).endswith(b"/hello"):
            pass

    def _take(self, deadline: float) -> bytes:
        left = deadline - time.monotonic()
        assert left > 0 and self.socket.poll(int(left * 1000)), "no sample before the deadline"
        topic, data = self.socket.recv_multipart()
        if not topic.endswith(b"/hello"):
            sample = msgpack.unpackb(data)
            if "ended" in sample:
                self.ended[sample["stream"]] = sample["ended"]
            else:
                self.live.add(sample["stream"])
        return bytes(topic)

    def until_ended(self, streams: set[str]) -> None:
        deadline = time.monotonic() + DEADLINE_S
        while not streams <= self.ended.keys():
            self._take(deadline)


def test_a_silent_client_loses_its_streams_and_their_places_are_free(
        daemon: EmbeddedDaemon) -> None:
    """Four raw clients fill the pool, then stop sending (as a SIGSTOPped process does):
    every stream ends with the sample a gone client's stream ends with, and another client
    may open streams again."""
    context = zmq.Context()
    try:
        watcher = Watcher(context, daemon)
        dealers = [context.socket(zmq.DEALER) for _ in range(MAX_STREAMS // PER_CLIENT)]
        opened: set[str] = set()
        for dealer in dealers:
            dealer.connect(control(daemon))
            for _ in range(PER_CLIENT):
                reply = call(dealer, "stream_states", {"rate": 5})
                assert reply["code"] == 0 and reply["result"]["silence_s"] == SILENCE_S
                opened.add(reply["result"]["stream"])
        for dealer in dealers:  # each heard from once more, then never again
            assert call(dealer, "status")["code"] == 0
        with Client(connect=daemon.zmq_endpoint) as other:
            with pytest.raises(ResourceLimitError) as full:
                other.call("stream_states", {"rate": 5})
            assert full.value.details == {"limit": "max_streams", "max": MAX_STREAMS}
            watcher.until_ended(opened)
            assert set(watcher.ended[s] for s in opened) == {"its client went"}
            again = other.call("stream_states", {"rate": 5})
            other.call("close_stream", {"stream": again["stream"]})
        assert call(dealers[0], "close_stream", {"stream": opened.pop()})["code"] != 0
    finally:
        context.destroy(linger=0)


def test_an_sdk_client_keeps_its_stream_past_the_silence(daemon: EmbeddedDaemon) -> None:
    """The SDK sends a status now and then while it holds a stream: beside a silent raw
    client's stream, which ends, its own goes on for a silence more (it is older)."""
    context = zmq.Context()
    try:
        watcher = Watcher(context, daemon)
        silent = context.socket(zmq.DEALER)
        silent.connect(control(daemon))
        with Client(connect=daemon.zmq_endpoint) as sim, \
                sim.stream_states(rate=20, timeout=DEADLINE_S) as kept:
            dropped = call(silent, "stream_states", {"rate": 5})["result"]["stream"]
            watcher.until_ended({dropped})
            until = time.monotonic() + SILENCE_S
            while (sample := kept.next()).ended is None and time.monotonic() < until:
                pass
            assert sample.ended is None, sample.ended
            assert kept.stream_id not in watcher.ended
    finally:
        context.destroy(linger=0)


class Flood:
    """Clients that keep the daemon's ROUTER never empty: each pipelines status requests
    as fast as ZeroMQ takes them and reads its replies, until stopped."""

    def __init__(self, context: zmq.Context, daemon: EmbeddedDaemon, clients: int) -> None:
        self.stop = threading.Event()
        self.answered = 0
        self.sockets = [context.socket(zmq.DEALER) for _ in range(clients)]
        for socket in self.sockets:
            socket.connect(control(daemon))
        self.threads = [threading.Thread(target=self._run, args=(s,)) for s in self.sockets]

    def _run(self, socket: zmq.Socket) -> None:
        request = msgpack.packb({"v": 1, "op": "status", "args": {}})
        while not self.stop.is_set():
            with contextlib.suppress(zmq.Again):
                while True:  # as many in flight as ZeroMQ holds: never a gap
                    socket.send(request, zmq.NOBLOCK)
            with contextlib.suppress(zmq.Again):
                while True:
                    socket.recv(zmq.NOBLOCK)
                    self.answered += 1

    def __enter__(self) -> Flood:
        for thread in self.threads:
            thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self.stop.set()
        for thread in self.threads:
            thread.join()


def test_under_a_flood_a_silent_client_loses_its_streams_and_a_live_one_keeps_them(
        daemon: EmbeddedDaemon) -> None:
    """With three clients flooding, the ROUTER is never read empty; ZeroMQ's fair queue
    still reads every waiting connection in turn, so silence is judged all the same: the
    silent raw client's stream ends, the SDK's (its pings read in their turn) goes on."""
    context = zmq.Context()
    try:
        watcher = Watcher(context, daemon)
        silent = context.socket(zmq.DEALER)
        silent.connect(control(daemon))
        with Client(connect=daemon.zmq_endpoint) as sim, \
                sim.stream_states(rate=20, timeout=DEADLINE_S) as kept, \
                Flood(context, daemon, clients=3) as flood:
            dropped = call(silent, "stream_states", {"rate": 5})["result"]["stream"]
            watcher.until_ended({dropped})
            assert watcher.ended[dropped] == "its client went"
            until = time.monotonic() + SILENCE_S
            while (sample := kept.next()).ended is None and time.monotonic() < until:
                pass
            assert sample.ended is None, sample.ended
            assert flood.answered > 100  # the flood was one
    finally:
        context.destroy(linger=0)


@pytest.mark.slow
def test_a_long_request_holding_the_daemon_ends_no_stream(daemon: EmbeddedDaemon) -> None:
    """Silence is counted while the daemon reads: a spawn that holds the physics thread
    past ``silence_s`` leaves the SDK's pings unread meanwhile, and its stream goes on."""
    count = 5000  # MuJoCo's compile is quadratic in free bodies: seconds
    poses = np.zeros((count, 7))
    poses[:, 0], poses[:, 2], poses[:, 6] = np.arange(count) * 0.3, 1.0, 1.0
    with Client(connect=daemon.zmq_endpoint, timeout=120.0) as sim, \
            sim.stream_states(rate=20, timeout=DEADLINE_S) as kept:
        kept.next()
        with Client(connect=daemon.zmq_endpoint, timeout=120.0) as other:
            started = time.monotonic()
            other.call("spawn", {"groups": [{
                "shape": "sphere", "size": [0.1], "names": [f"held{i}" for i in range(count)],
                "poses": pack_f64(poses)}]})
            held = time.monotonic() - started
            if held < 1.5 * SILENCE_S:
                pytest.skip(f"the spawn held the daemon {held:.1f} s only: nothing to test")
            until = time.monotonic() + SILENCE_S
            while (sample := kept.next()).ended is None and time.monotonic() < until:
                pass
            assert sample.ended is None, f"held {held:.1f} s: {sample.ended}"
            other.call("reset", {"scope": "all"})


def test_a_turn_of_the_fair_queue_drains_what_waited_when_it_began(tmp_path: Path) -> None:
    """Under a flood the ROUTER is never read empty; once a connection is read a second
    time, ZeroMQ's fair queue has read every connection that had a message waiting when
    the turn began, so the turn's start is when everything sent before it had been read."""
    front = ZmqFront([f"ipc://{tmp_path}/ctl.sock"], "turns", silence_s=SILENCE_S)
    try:
        for identity, now in ((b"a", 1.0), (b"b", 2.0), (b"c", 2.5)):
            front._turn(0, identity, now)
        assert front.drained[0] == 0.0  # a turn under way drains nothing yet
        front._turn(0, b"a", 3.0)  # a again: the turn that began at 1.0 is whole
        assert front.drained[0] == 1.0
        front._turn(0, b"b", 4.0)
        front._turn(0, b"b", 5.0)
        assert front.drained[0] == 3.0
    finally:
        front.close()
