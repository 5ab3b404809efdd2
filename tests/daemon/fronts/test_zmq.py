"""The ZeroMQ front as a client written from docs/protocol.md sees it: raw pyzmq sockets
against real daemons (the conformance suite runs every operation over it through the SDK)."""

from __future__ import annotations

import importlib.util
import json
import os
import queue
import signal
import subprocess
import threading
from pathlib import Path

import msgpack
import pytest
import zmq
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon, discover_at
from galton.client.sdk.embedded import daemon_command, free_loopback_port
from galton.daemon.fronts.zmq import telemetry_endpoint
from galton.protocol import DaemonUnreachableError, InvalidArgumentError

ROOT = Path(__file__).resolve().parents[3]
REPLY_WAIT_MS = 20_000


def envelope(op: str, args: dict | None = None) -> bytes:
    return msgpack.packb({"v": 1, "op": op, "args": args or {}}, use_bin_type=True)


@pytest.fixture
def zmq_daemon(daemons: dict[str, EmbeddedDaemon]) -> EmbeddedDaemon:
    """The session's MuJoCo daemon on a fresh world."""
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint) as sim:
        sim.load_world("mujoco")
    return daemon


@pytest.fixture
def dealer(zmq_daemon: EmbeddedDaemon) -> zmq.Socket:
    context = zmq.Context()
    socket = context.socket(zmq.DEALER)
    assert zmq_daemon.zmq_endpoint is not None
    socket.connect(zmq_daemon.zmq_endpoint.removeprefix("zmq+"))
    yield socket
    context.destroy(linger=0)


def receive(socket: zmq.Socket) -> list[bytes]:
    assert socket.poll(REPLY_WAIT_MS), "no reply"
    return socket.recv_multipart()


def test_a_raw_pyzmq_msgpack_client_works(zmq_daemon: EmbeddedDaemon) -> None:
    spec = importlib.util.spec_from_file_location("raw_zmq", ROOT / "examples" /
                                                  "raw_zmq_client.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert zmq_daemon.zmq_endpoint is not None
    heights, sample = module.main(zmq_daemon.zmq_endpoint.removeprefix("zmq+"))
    # On the ground it spawns (issue 47: they fell through to -2.9 m): radius 0.1 m, piled
    # at most a few deep, none through the plane.
    assert len(heights) == 100 and max(heights) < 2.0 and min(heights) > 0.05
    assert sample["instance"] == zmq_daemon.instance and sample["step"] >= 500


def test_a_req_socket_sends_the_envelope_alone(zmq_daemon: EmbeddedDaemon) -> None:
    context = zmq.Context()
    try:
        socket = context.socket(zmq.REQ)
        socket.connect(zmq_daemon.zmq_endpoint.removeprefix("zmq+"))  # type: ignore[union-attr]
        socket.send(envelope("status"))
        reply = msgpack.unpackb(receive(socket)[0])
        assert reply["code"] == 0 and reply["result"]["instance"] == zmq_daemon.instance
    finally:
        context.destroy(linger=0)


def test_replies_come_as_requests_finish_each_with_its_tag(dealer: zmq.Socket) -> None:
    """A long step sent first answers after a status sent second; the tags tell them
    apart, and a pause ends the step."""
    dealer.send_multipart([b"step", envelope("step", {"count": 10**9})])
    dealer.send_multipart([b"status", envelope("status")])
    tag, reply = receive(dealer)
    assert tag == b"status" and msgpack.unpackb(reply)["code"] == 0
    dealer.send_multipart([b"pause", envelope("pause")])
    answered = dict(receive(dealer) for _ in range(2))
    assert msgpack.unpackb(answered[b"pause"])["code"] == 0
    step = msgpack.unpackb(answered[b"step"])
    assert step["code_name"] == "OPERATION_FAILED" and "interrupted" in step["message"]


def test_a_closed_holder_loses_control_when_a_new_connection_takes_its_fd(
        zmq_daemon: EmbeddedDaemon, dealer: zmq.Socket) -> None:
    """A connection that closes while the physics thread is busy, followed at once by a new
    one (which gets the same file descriptor), used to have its closing blamed on the new
    one: the lease of the closed holder was never lost, and the new connection's was."""
    endpoint = zmq_daemon.zmq_endpoint.removeprefix("zmq+")  # type: ignore[union-attr]
    dealer.send_multipart([b"step", envelope("step", {"count": 10**9})])  # keeps it busy
    events: queue.Queue[dict] = queue.Queue()
    context = zmq.Context()
    try:
        # Over ZeroMQ: the subscription returns once in place (a Zenoh one may miss the
        # first events while it propagates).
        with Client(connect=zmq_daemon.zmq_endpoint) as watcher, watcher.on_event(events.put):
            for _ in range(5):
                holder = context.socket(zmq.DEALER)
                holder.connect(endpoint)
                holder.send_multipart([b"take", envelope("take_control")])
                assert msgpack.unpackb(receive(holder)[1])["result"]["taken"]
                holder.close(linger=0)
                newcomer = context.socket(zmq.DEALER)
                newcomer.connect(endpoint)
                newcomer.send_multipart([b"status", envelope("status")])
                receive(newcomer)
                while (event := events.get(timeout=10))["kind"] != "control" or \
                        event["change"] != "lost":
                    pass  # the "taken" event, state changes
                newcomer.close(linger=0)
    finally:
        context.destroy(linger=0)
        dealer.send_multipart([b"pause", envelope("pause")])
        receive(dealer)


@pytest.mark.parametrize("frames", [
    [b"x"] * 8 + [envelope("status")],  # 9 frames: more than 8
    [b"x" * 257, envelope("status")],  # a routing frame past 256 bytes
], ids=["too-many-frames", "long-routing-frame"])
def test_a_message_with_no_address_is_dropped_and_serving_goes_on(
        dealer: zmq.Socket, frames: list[bytes]) -> None:
    dealer.send_multipart(frames)
    dealer.send_multipart([b"after", envelope("status")])
    tag, reply = receive(dealer)  # the first reply is the second request's: none came before
    assert tag == b"after" and msgpack.unpackb(reply)["code"] == 0


def test_a_message_of_eight_frames_is_answered(dealer: zmq.Socket) -> None:
    """protocol.md drops a message of *more* than 8 frames: one of 8 (7 routing frames and
    the envelope) was dropped too, the ROUTER's identity frame counted as the client's."""
    routing = [b"r%d" % i for i in range(7)]
    dealer.send_multipart([*routing, envelope("status")])
    *echoed, reply = receive(dealer)
    assert echoed == routing and msgpack.unpackb(reply)["code"] == 0


@pytest.mark.parametrize("payload, code", [
    (b"\xc1", "MALFORMED_REQUEST"),
    (msgpack.packb({"v": 1, "args": {}}), "MALFORMED_REQUEST"),  # no op: no key to say it
    (msgpack.packb({"v": 2, "op": "status"}), "UNSUPPORTED_VERSION"),
    (envelope("no_such_op"), "UNKNOWN_OPERATION"),
], ids=["not-msgpack", "no-op", "version-2", "unknown-op"])
def test_a_bad_envelope_gets_its_code(dealer: zmq.Socket, payload: bytes, code: str) -> None:
    dealer.send_multipart([b"t", payload])
    tag, reply = receive(dealer)
    assert tag == b"t" and msgpack.unpackb(reply)["code_name"] == code


def test_capabilities_and_discovery_name_the_endpoints(zmq_daemon: EmbeddedDaemon) -> None:
    endpoint = zmq_daemon.zmq_endpoint.removeprefix("zmq+")  # type: ignore[union-attr]
    with Client(zmq_daemon.instance, zmq_daemon.endpoint) as sim:
        advertised = sim.capabilities().zmq
    assert advertised == {"control": [endpoint], "telemetry": [endpoint + ".pub"]}
    found = {d.instance: d for d in discover_at(zmq_daemon.endpoint)}
    assert found[zmq_daemon.instance].zmq == [endpoint]


def test_events_reach_an_sdk_client_over_zmq(zmq_daemon: EmbeddedDaemon) -> None:
    seen: queue.Queue[dict] = queue.Queue()
    with Client(connect=zmq_daemon.zmq_endpoint) as sim, sim.on_event(seen.put):
        with sim.telemetry(timeout=10) as stream:
            next(stream)  # the subscription is connected: what follows is not missed
        sim.play()
        sim.pause()
        kinds = [seen.get(timeout=10)["state"] for _ in range(2)]
    assert kinds == ["playing", "paused"]


def test_closing_a_client_ends_its_live_subscriptions_cleanly(
        zmq_daemon: EmbeddedDaemon, monkeypatch: pytest.MonkeyPatch) -> None:
    """A subscription left open when its client closes ends with it, as over Zenoh: its
    socket was closed under its thread's poll, which died with a ZMQError."""
    failures: list[BaseException | None] = []
    monkeypatch.setattr(threading, "excepthook", lambda args: failures.append(args.exc_value))
    sim = Client(connect=zmq_daemon.zmq_endpoint)
    arrived = threading.Event()
    sim.on_telemetry(lambda sample: arrived.set())  # never closed by the test
    assert arrived.wait(10)
    threads = [t for t in threading.enumerate() if t.name == "galton-zmq-sub"]
    sim.close()
    for thread in threads:
        thread.join(10)
    assert not failures and not any(thread.is_alive() for thread in threads)


def test_bad_zmq_endpoints_are_refused_at_start() -> None:
    for value in ("ftp://host:1", "tcp://nohost", "ipc://"):
        done = subprocess.run([*daemon_command(), "--zmq", value, "--listen",
                               f"tcp/127.0.0.1:{free_loopback_port()}"],
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == 2 and "is not an endpoint" in done.stderr, done.stderr


def test_an_abstract_ipc_socket_is_refused_at_start() -> None:
    """``ipc://@name`` has no file, so none of the permissions docs/SECURITY.md promises,
    and the SDK refused it ("no socket file"): it used to be served all the same."""
    done = subprocess.run([*daemon_command(), "--zmq", "ipc://@galton-abstract", "--listen",
                           f"tcp/127.0.0.1:{free_loopback_port()}"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "abstract socket" in done.stderr, done.stderr


@pytest.mark.parametrize("taken", ["", ".pub"], ids=["control", "telemetry"])
def test_an_ipc_path_that_is_a_file_is_refused_and_kept(tmp_path: Path, taken: str) -> None:
    """ZeroMQ deletes whatever is at an ipc path it binds: a daemon started on a file's
    name (a typo) used to delete that file, or the file beside it named PATH.pub."""
    path = tmp_path / "notes"
    Path(f"{path}{taken}").write_text("keep me")
    done = subprocess.run([*daemon_command(), "--zmq", f"ipc://{path}", "--listen",
                           f"tcp/127.0.0.1:{free_loopback_port()}"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "is no socket" in done.stderr, done.stderr
    assert Path(f"{path}{taken}").read_text() == "keep me"


def test_a_port_in_use_is_refused_at_start() -> None:
    """The daemon used to hang for ever here: the ROUTER that failed to bind was never
    closed, and closing the ZeroMQ context waits for every socket."""
    context = zmq.Context()
    try:
        taken = context.socket(zmq.ROUTER)
        taken.bind("tcp://127.0.0.1:*")
        endpoint = taken.getsockopt_string(zmq.LAST_ENDPOINT)
        done = subprocess.run([*daemon_command(), "--zmq", endpoint, "--listen",
                               f"tcp/127.0.0.1:{free_loopback_port()}"],
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == 2 and "could not bind" in done.stderr, done.stderr
    finally:
        context.destroy(linger=0)


def test_a_tcp_daemon_on_any_port_then_killed(tmp_path: Path) -> None:
    """``tcp://127.0.0.1:*`` binds free ports that capabilities names; an ipc socket file
    goes when the daemon stops; a client of a killed daemon hears "unreachable"."""
    socket_file = tmp_path / "d.sock"
    daemon = EmbeddedDaemon("mujoco", instance="zmq-any-port", extra_args=[
        "--zmq", "tcp://127.0.0.1:*", "--zmq", f"ipc://{socket_file}"]).start()
    try:
        with Client(daemon.instance, daemon.endpoint) as sim:
            control, telemetry = sim.capabilities().zmq.values()
        assert control[0].startswith("tcp://127.0.0.1:") and control[1] == f"ipc://{socket_file}"
        # Its own free port, not the next one (which another process may hold): Linux gives
        # bind(0) ports of one parity, so two free ports are never neighbours.
        assert port(telemetry[0]) != port(control[0]) + 1, (control, telemetry)
        assert telemetry[1] == f"ipc://{socket_file}.pub" and socket_file.exists()
        with Client(connect=f"zmq+{control[0]}") as sim:
            assert sim.status().instance == daemon.instance
            os.kill(daemon.process.pid, signal.SIGKILL)  # type: ignore[union-attr]
            daemon.process.wait(30)  # type: ignore[union-attr]
            with pytest.raises(DaemonUnreachableError):
                sim.status()
    finally:
        daemon.stop()
    daemon = EmbeddedDaemon("mujoco", instance="zmq-any-port", extra_args=[
        "--zmq", f"ipc://{socket_file}"]).start()  # a stale socket file is bound over
    assert daemon.stop() == 0 and not socket_file.exists()


def port(endpoint: str) -> int:
    return int(endpoint.rpartition(":")[2])


@pytest.mark.parametrize("control, telemetry", [
    ("tcp://127.0.0.1:5555", "tcp://127.0.0.1:5556"),
    ("tcp://127.0.0.1:*", "tcp://127.0.0.1:*"),
    ("tcp://127.0.0.1:0", "tcp://127.0.0.1:*"),  # ZeroMQ's other "any port", not port 1
    ("ipc:///run/g.sock", "ipc:///run/g.sock.pub"),
])
def test_the_telemetry_endpoint_beside_a_control_one(control: str, telemetry: str) -> None:
    assert telemetry_endpoint(control) == telemetry


def test_an_ipc_path_a_running_daemon_serves_is_not_taken_from_it(tmp_path: Path) -> None:
    """A second daemon on the same ipc path is refused at start (ZeroMQ would bind over the
    file and leave the first one unreachable); a process that binds the path anyway keeps
    its file when the daemon stops (the daemon used to remove it)."""
    socket_file = tmp_path / "shared.sock"
    daemon = EmbeddedDaemon("mujoco", instance="zmq-shared-path", extra_args=[
        "--zmq", f"ipc://{socket_file}"]).start()
    context = zmq.Context()
    try:
        done = subprocess.run([*daemon_command(), "--zmq", f"ipc://{socket_file}", "--listen",
                               f"tcp/127.0.0.1:{free_loopback_port()}"],
                              capture_output=True, text=True, timeout=60)
        assert done.returncode == 2 and "serves that socket already" in done.stderr, done.stderr
        with Client(connect=f"zmq+ipc://{socket_file}") as sim:
            assert sim.status().instance == daemon.instance
        intruder = context.socket(zmq.ROUTER)
        intruder.bind(f"ipc://{socket_file}")  # what docs/SECURITY.md warns of
        assert daemon.stop() == 0
        assert socket_file.exists()  # the intruder's file, not the daemon's
    finally:
        daemon.stop()
        context.destroy(linger=0)


def test_sdk_endpoints_that_reach_nothing_are_unreachable(tmp_path: Path) -> None:
    with pytest.raises(DaemonUnreachableError, match="no socket file"):
        Client(connect=f"zmq+ipc://{tmp_path}/none.sock")
    with pytest.raises(DaemonUnreachableError, match="no galton-daemon answers"):
        Client(connect=f"zmq+tcp://127.0.0.1:{free_loopback_port()}")
    with pytest.raises(InvalidArgumentError, match="not a ZeroMQ endpoint"):
        Client(connect="zmq+udp://127.0.0.1:1")


@pytest.mark.parametrize("endpoint", ["zmq+tcp://nohost", "zmq+tcp://127.0.0.1:port"])
def test_an_endpoint_zeromq_cannot_parse_is_a_typed_error(endpoint: str) -> None:
    """libzmq's own "Invalid argument" used to escape as a bare ZMQError."""
    with pytest.raises(InvalidArgumentError, match="not a ZeroMQ endpoint"):
        Client(connect=endpoint)


def test_galton_client_daemons_shows_the_zmq_endpoints(zmq_daemon: EmbeddedDaemon) -> None:
    from support.cli import run

    result = run(["--connect", zmq_daemon.endpoint, "daemons"])  # the table's own column
    assert result.exit_code == 0 and "Zero" in result.stdout, result.output
    found = {d["instance"]: d for d in json.loads(
        run(["--connect", zmq_daemon.endpoint, "daemons", "--json"]).stdout)}
    assert found[zmq_daemon.instance]["zmq"] == [
        zmq_daemon.zmq_endpoint.removeprefix("zmq+")]  # type: ignore[union-attr]

