"""The daemon's ZeroMQ front: ROUTER sockets for requests and one XPUB socket for telemetry
and events, beside Zenoh, on the same host or a trusted link (docs/protocol.md, "ZeroMQ").

No thread of its own and no hand-off: the physics thread polls the sockets between steps
(the core's ``PolledInbox``, daemon/core/inbox.py, given this front as its ``PolledSource``),
reads a request, answers it, and sends the reply itself. ZeroMQ sockets
are not thread-safe, so every socket here is used on the physics thread only; requests that
come over Zenoh are queued as before and wake the poll through a pipe.

A long step is tied to the connection it came on: a socket monitor reports each closed
connection by its file descriptor, which the first request on it mapped to the peer.
A connection that sends nothing for ``silence_s`` (the ``zmq_silence_s`` limit) is gone
for ``client_alive``: the core ends its state streams (a stopped client's connection stays
open; the SDK sends a ``status`` now and then while it holds streams).
"""

from __future__ import annotations

import contextlib
import errno
import os
import select
import socket as sockets
import stat
import time
from collections.abc import Callable, Iterator
from typing import Any

import zmq
from zmq.backend.cython._zmq import Socket as BaseSocket
from zmq.utils.monitor import parse_monitor_message

from galton.daemon.access.zmq_auth import ZmqSecurity, start_authenticator
from galton.daemon.core.calls import Call, CallPort, PolledSource, Task
from galton.daemon.fronts.base import Front
from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

# pyzmq's flag enums cost more than the calls they flag (about 1 µs per operation): ints.
_EVENTS, _POLLIN = int(zmq.EVENTS), int(zmq.POLLIN)
_NOBLOCK, _MORE, _SRCFD = int(zmq.NOBLOCK), int(zmq.SNDMORE | zmq.NOBLOCK), int(zmq.SRCFD)
# The base class's send and recv: pyzmq's wrappers add about 1 µs per frame.
_send: Callable[..., Any] = BaseSocket.send
_recv: Callable[..., Any] = BaseSocket.recv
_get: Callable[..., Any] = BaseSocket.get
MONITOR_PERIOD_S = 0.05  # closed connections and subscribers are looked for this often
# A message is routing frames (echoed in the reply, as ZeroMQ's REQ/DEALER envelopes are),
# then one frame holding the request: at most this many frames as the client sent them
# (the ROUTER's identity frame in front is not counted: protocol.md speaks of the client's).
MAX_FRAMES = 8
MAX_ROUTING_FRAME_BYTES = 256
# Per connection, in each direction: requests ZeroMQ holds for the daemon before it stops
# reading that connection (the client's sends then wait: back-pressure on it alone), and
# replies it holds for a client that does not read them before it drops the newest (a client
# that never reads cannot grow the daemon). Fairness: ``receive`` takes one request per
# ROUTER per call, which ZeroMQ deals out fairly between connections (issue 35, item 8).
MAX_QUEUED_PER_CONNECTION = 64
# No ZMTP heartbeats (a liveness check of each connection): with libzmq 4.3.5 a heartbeat
# timer firing after an I/O error aborts the process ("Assertion failed: !_io_error
# (src/stream_engine_base.cpp:310)"), seen under the test suite's load (issue 46). A stopped
# client keeps its connection, and so its place in the step queue; its state streams end
# when it has been silent for ``silence_s`` (an application-level keepalive: ``client_alive``).
LOOPBACK = "127.0.0.1"


def parse_endpoint(text: str) -> str:
    """A ``--zmq`` value as a ZeroMQ endpoint: ``ipc://PATH``, ``tcp://HOST:PORT`` (PORT may
    be ``*``: any free port), or a bare port, which means loopback (``tcp://127.0.0.1:PORT``)."""
    text = text.strip()
    if text.isdigit():
        text = f"tcp://{LOOPBACK}:{text}"
    if text.startswith("ipc://@"):
        raise InvalidArgumentError(
            f"--zmq {brief(text)} is an abstract socket, which has no file and so no "
            "permissions: every account on the host could connect to it (and the SDK "
            "looks for a file); give ipc:///path/to/socket")
    if text.startswith("ipc://") and len(text) > len("ipc://"):
        return text
    if text.startswith("tcp://"):
        host, _, port = text[len("tcp://"):].rpartition(":")
        if host and (port == "*" or (port.isdigit() and 0 <= int(port) <= 65535)):
            return text
    raise InvalidArgumentError(
        f"--zmq {brief(text)} is not an endpoint: give ipc:///path/to/socket, "
        "tcp://HOST:PORT (PORT may be '*') or a port number (loopback)")


def telemetry_endpoint(control: str) -> str:
    """Where the PUB socket of a control endpoint is bound: ``ipc://PATH.pub``, or the next
    TCP port (a ``*`` or ``0`` port gives any free port: the bound one is advertised)."""
    if control.startswith("ipc://"):
        return control + ".pub"
    host, _, port = control[len("tcp://"):].rpartition(":")
    return (f"tcp://{host}:*" if port == "*" or int(port) == 0
            else f"tcp://{host}:{int(port) + 1}")


class ZmqFront(Front):
    """The ZeroMQ ``Front`` (daemon/fronts/base.py) and the core's ``PolledSource``: the bound
    sockets, the monitor of each ROUTER and the pipe that wakes the poll."""

    def __init__(self, endpoints: list[str], instance: str,
                 security: ZmqSecurity | None = None, *, silence_s: float) -> None:
        self.context = zmq.Context()
        self.silence_s = silence_s
        self.security = security
        self.authenticator = (start_authenticator(self.context, security)
                              if security is not None else None)
        self.routers: list[zmq.Socket[bytes]] = []
        self.monitors: list[zmq.Socket[bytes]] = []
        # Per ROUTER: the peer identity each connection's file descriptor carries, and back.
        self.peers: list[dict[int, bytes]] = []
        self.known: list[dict[bytes, int]] = []
        # Per ROUTER: when each peer was last heard from (its last message's receive), and
        # the latest moment by which everything sent to us had been read (``drained``): a
        # peer is silent only if, with everything it sent read, we had not heard from it
        # for silence_s (a physics thread held by a long request has not read the pings
        # waiting meanwhile). Read empty, the ROUTER is drained now; under a flood it never
        # is, but ZeroMQ hands out its connections' messages in turn, so once a connection
        # is read twice every connection that had a message waiting when that turn began
        # has been read in it: the turn's start is drained (``_turn``).
        self.heard: list[dict[bytes, float]] = []
        self.drained: list[float] = []
        self.turn_read: list[set[bytes]] = []  # per ROUTER: who was read in this turn
        self.turn_start: list[float] = []
        self.control: list[str] = []
        self.telemetry: list[str] = []
        self.files: dict[str, tuple[int, int]] = {}  # our ipc socket files: (device, inode)
        self.prefix = f"galton/{instance}/".encode()
        try:
            # An XPUB: it reads each new subscription, and answers it with a "hello" the
            # subscriber waits for, so that nothing published after that is missed.
            self.pub = self.context.socket(zmq.XPUB)
            self.pub.setsockopt(zmq.LINGER, 0)
            self.pub.setsockopt(zmq.XPUB_VERBOSE, 1)
            if security is not None:
                security.secure(self.pub)
            for endpoint in endpoints:
                self._bind(endpoint)
        except zmq.ZMQError as error:
            self.close()
            raise InvalidArgumentError(f"ZeroMQ could not bind: {error}") from error
        except InvalidArgumentError:
            self.close()
            raise
        self._wake_read, self._wake_write = os.pipe()
        os.set_blocking(self._wake_read, False)
        os.set_blocking(self._wake_write, False)
        self._fds: list[int] = [int(socket.getsockopt(zmq.FD)) for socket in (
            *self.routers, *self.monitors, self.pub)] + [self._wake_read]
        self._side_fds = self._fds[len(self.routers):-1]  # the monitors' and the XPUB's
        self._next_side_check = 0.0

    def _bind(self, endpoint: str) -> None:
        router = self.context.socket(zmq.ROUTER)
        try:
            self._bind_router(router, endpoint)
        except BaseException:
            if router not in self.routers:  # close() would not close it, and the context's
                router.close(linger=0)  # term() would wait for it for ever
            raise

    def _bind_router(self, router: zmq.Socket[bytes], endpoint: str) -> None:
        router.setsockopt(zmq.LINGER, 0)
        router.setsockopt(zmq.RCVHWM, MAX_QUEUED_PER_CONNECTION)
        router.setsockopt(zmq.SNDHWM, MAX_QUEUED_PER_CONNECTION)
        if self.security is not None:
            self.security.secure(router)
        _refuse_if_served(endpoint)
        with _private_files():
            router.bind(endpoint)
        self.routers.append(router)
        self.monitors.append(router.get_monitor_socket(zmq.EVENT_DISCONNECTED))
        self.peers.append({})
        self.known.append({})
        self.heard.append({})
        self.drained.append(0.0)
        self.turn_read.append(set())
        self.turn_start.append(0.0)
        bound = router.getsockopt_string(zmq.LAST_ENDPOINT)
        self.control.append(bound)
        self._own(bound)
        # From the endpoint asked for: a '*' port's bound one is a number, and its next port
        # is no free port (another process may hold it).
        telemetry = telemetry_endpoint(bound if bound.startswith("ipc://") else endpoint)
        _refuse_if_served(telemetry)
        with _private_files():
            self.pub.bind(telemetry)
        self.telemetry.append(self.pub.getsockopt_string(zmq.LAST_ENDPOINT))
        self._own(self.telemetry[-1])

    def _own(self, bound: str) -> None:
        """Remember which file an ipc endpoint is, so that ``close`` removes only ours."""
        if bound.startswith("ipc://"):
            with contextlib.suppress(OSError):  # gone already: nothing to remove at close
                found = os.stat(bound[len("ipc://"):])
                self.files[bound] = (found.st_dev, found.st_ino)

    def open(self, core: CallPort) -> None:
        """Nothing to start: the core polls this front (as its ``PolledSource``) from the
        moment its physics thread runs, and answers each call on that thread."""

    def withdraw(self) -> None:
        """Nothing to withdraw: ZeroMQ has no liveliness; the sockets close at ``close``."""

    def advertised(self) -> dict[str, Any]:
        """The endpoints as ``capabilities`` names them, with the CURVE public key (Z85) a
        client needs when the front is encrypted."""
        found: dict[str, Any] = {"control": list(self.control),
                                 "telemetry": list(self.telemetry)}
        if self.security is not None:
            found["server_key"] = self.security.public_key.decode()
        return {"zmq": found}

    def ready_words(self) -> str:
        return f"zmq={','.join(self.control)}"

    def polled(self) -> PolledSource:
        """The physics thread reads this front's sockets itself (no thread hand-off)."""
        return self

    def wake(self) -> None:
        """Called from any thread: make a waiting ``wait`` return."""
        with contextlib.suppress(BlockingIOError):  # a full pipe wakes the poll anyway
            os.write(self._wake_write, b"\0")

    def wait(self, timeout: float | None) -> None:
        """Wait until a socket may be readable, the pipe is woken, or ``timeout`` seconds
        (select(): microsecond resolution, unlike zmq_poll's milliseconds).

        Call it right after ``receive`` found nothing, with no send on a ROUTER between:
        ZMQ_FD is edge-triggered, and ``receive``'s last look at ZMQ_EVENTS re-armed it."""
        try:
            ready, _, _ = select.select(self._fds, [], [], timeout)
        except InterruptedError:
            return
        if self._wake_read in ready:
            with contextlib.suppress(BlockingIOError):
                os.read(self._wake_read, 4096)
        if any(fd in ready for fd in self._side_fds):
            self._next_side_check = 0.0  # a connection closed or a subscriber came: look now

    def receive(self, gone: Callable[[str], Task]) -> list[Call | Task]:
        """What is readable now, without blocking: closed connections first (as Tasks
        made by ``gone``), then at most one request per ROUTER as a Call answered on this
        thread (ZeroMQ queues each connection's apart and hands them out in turn: one
        client's pipelined flood waits behind every other client's next request)."""
        items: list[Call | Task] = []
        now = time.monotonic()
        if now >= self._next_side_check:  # off the hot path: neither is urgent
            self._next_side_check = now + MONITOR_PERIOD_S
            self._welcome_subscribers()
            for index in range(len(self.monitors)):
                self._take_closed(index, gone, items)
        for index, router in enumerate(self.routers):
            while True:
                if not _has_input(router):
                    self.drained[index] = now
                    self.turn_read[index].clear()
                    break
                call = self._call(index, router, gone, items, now)
                if call is not None:
                    items.append(call)
                    break
        return items

    def client_alive(self, client: str) -> bool | None:
        """For a connection's name (``peer_name``): False once it has closed, or sent
        nothing for ``silence_s`` while the daemon was reading; True else. None for a name
        that is none of ours (a Zenoh client id)."""
        found = parse_peer_name(client)
        if found is None or not 0 <= found[0] < len(self.routers):
            return None
        index, identity = found
        heard = self.heard[index].get(identity)
        if heard is None:
            return False  # closed (or never seen): its close ends what it held
        return self.drained[index] - heard <= self.silence_s

    def _take_closed(self, index: int, gone: Callable[[str], Task],
                     items: list[Call | Task]) -> None:
        """The connections of ROUTER ``index`` closed since the last look, as Tasks."""
        monitor = self.monitors[index]
        while _has_input(monitor):  # no recv that fails: a zmq.Again costs ~3 µs
            event = parse_monitor_message(monitor.recv_multipart())
            identity = self.peers[index].pop(int(event["value"]), None)
            if identity is not None:
                self.known[index].pop(identity, None)
                self.heard[index].pop(identity, None)
                items.append(gone(peer_name(index, identity)))

    def _call(self, index: int, router: zmq.Socket[bytes], gone: Callable[[str], Task],
              items: list[Call | Task], now: float) -> Call | None:
        """A Call for the message waiting on ``router``; a message that is no request is
        dropped, as ZeroMQ cannot address an answer to a malformed envelope."""
        first = frame = _recv(router, 0, False)  # the peer's identity: it knows its fd
        frames: list[bytes] = [first.bytes]
        while frame.more:
            frame = _recv(router, 0, False)
            frames.append(frame.bytes)
        routing, payload = frames[:-1], frames[-1]
        self._turn(index, frames[0], now)
        if frames[0] in self.known[index]:
            self.heard[index][frames[0]] = now  # any message counts, a malformed one too
        if len(frames) < 2 or len(frames) - 1 > MAX_FRAMES or any(
                len(part) > MAX_ROUTING_FRAME_BYTES for part in routing[1:]):
            return None
        if routing[0] not in self.known[index]:
            # A new connection may have the fd of one closed since the monitors were last
            # read: that one's close is taken first, or it would be blamed on this one.
            self._take_closed(index, gone, items)
            fd = int(first.get(_SRCFD))
            self.peers[index][fd] = routing[0]
            self.known[index][routing[0]] = fd
            self.heard[index][routing[0]] = now

        def respond(data: bytes) -> None:
            # A peer whose queue is full, or which has gone, loses it (as ROUTER would):
            # ROUTER takes or drops a whole message at its first frame.
            with contextlib.suppress(zmq.Again):
                for part in routing:
                    _send(router, part, _MORE)
                _send(router, data, _NOBLOCK)
        role = (self.security.role_of(first.get("User-Id"))
                if self.security is not None else None)
        return Call("", payload, respond, peer=peer_name(index, routing[0]), role=role)

    def _turn(self, index: int, identity: bytes, now: float) -> None:
        """Count one message of ``identity`` read from ROUTER ``index`` in ZeroMQ's turn
        (its fair queue): a connection read again starts a new turn, and the one that ends
        drained the ROUTER of what was waiting when it began."""
        read = self.turn_read[index]
        if identity in read:
            self.drained[index] = max(self.drained[index], self.turn_start[index])
            read.clear()
        if not read:
            self.turn_start[index] = now
        read.add(identity)

    def _welcome_subscribers(self) -> None:
        """Publish one "hello" after any new subscription the XPUB has read: a subscriber
        that receives it knows its subscription is in place (ZeroMQ's slow joiner)."""
        subscribed = False
        while _has_input(self.pub):
            subscribed |= self.pub.recv()[:1] == b"\x01"
        if subscribed:
            self.publish("hello", b"")

    def publish(self, topic: str, data: bytes) -> None:
        """Publish on ``galton/<instance>/<topic>`` (the Zenoh key, as the topic frame)."""
        with contextlib.suppress(zmq.Again):
            self.pub.send_multipart([self.prefix + topic.encode(), data], zmq.NOBLOCK)
        # A send may take the XPUB's edge-triggered ZMQ_FD signal of a new subscription:
        # the next receive() reads its ZMQ_EVENTS (and so re-arms it) before any sleep.
        self._next_side_check = 0.0

    def close(self) -> None:
        """Close every socket (after the physics thread has stopped using them)."""
        for router in self.routers:
            router.disable_monitor()
        for socket in (*self.monitors, *self.routers):
            socket.close(linger=0)
        if hasattr(self, "pub"):
            self.pub.close(linger=0)
        if self.authenticator is not None:
            self.authenticator.stop()
        for endpoint, identity in self.files.items():
            _remove_socket_file(endpoint, identity)
        for fd in (getattr(self, "_wake_read", None), getattr(self, "_wake_write", None)):
            if fd is not None:
                os.close(fd)
        self.context.term()


@contextlib.contextmanager
def _private_files() -> Iterator[None]:
    """An ipc socket file that neither other users can write (connect to) nor read: only the
    daemon's user and group (at start, on the physics thread: no other file is made then)."""
    previous = os.umask(0o007)
    try:
        yield
    finally:
        os.umask(previous)


def _has_input(socket: zmq.Socket[bytes]) -> bool:
    """Whether a whole message waits (reading ZMQ_EVENTS also re-arms ZMQ_FD)."""
    return bool(_get(socket, _EVENTS) & _POLLIN)


PEER_PREFIX = "@zmq:"  # '@': no client id starts so, so no Zenoh client passes for one


def peer_name(index: int, identity: bytes) -> str:
    """The name a connection goes by in the loop (a step job's client, a stream's owner)."""
    return f"{PEER_PREFIX}{index}:{identity.hex()}"


def parse_peer_name(name: str) -> tuple[int, bytes] | None:
    """The ROUTER index and peer identity of a ``peer_name``, else None."""
    if not name.startswith(PEER_PREFIX):
        return None
    index, _, identity = name[len(PEER_PREFIX):].partition(":")
    try:
        return int(index), bytes.fromhex(identity)
    except ValueError:
        return None


def _remove_socket_file(endpoint: str, identity: tuple[int, int]) -> None:
    """Remove an ipc socket file if it is still ours: a process that bound the path since
    (docs/SECURITY.md) keeps its own."""
    path = endpoint[len("ipc://"):]
    try:
        found = os.stat(path)
        if (found.st_dev, found.st_ino) == identity:
            os.unlink(path)
    except OSError as error:
        if error.errno != errno.ENOENT:
            raise


def _refuse_if_served(endpoint: str) -> None:
    """ZeroMQ binds an ipc path over an existing socket file: one that a running process
    still serves would be taken from it, its new clients sent here. Refused, as TCP refuses
    a port in use; a stale file (nobody listening) is bound over."""
    if not endpoint.startswith("ipc://") or endpoint == "ipc://*":
        return
    path = endpoint[len("ipc://"):]
    with contextlib.suppress(OSError):
        if not stat.S_ISSOCK(os.stat(path).st_mode):  # ZeroMQ would delete it, say a file
            raise InvalidArgumentError(  # named by a typo
                f"--zmq {endpoint}: {path} exists and is no socket: give a path that is "
                "free or a socket file (it would be replaced)")
    probe = sockets.socket(sockets.AF_UNIX, sockets.SOCK_STREAM)
    try:
        probe.settimeout(1.0)
        probe.connect(path)
    except OSError:
        return  # no such file, or nobody listens on it
    finally:
        probe.close()
    raise InvalidArgumentError(
        f"--zmq {endpoint}: a running process serves that socket already (another "
        "galton-daemon?): stop it, or give another path")

