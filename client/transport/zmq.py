"""The SDK over ZeroMQ: a DEALER socket per calling thread to one daemon's ROUTER, and a
SUB socket per subscription (docs/protocol.md, "ZeroMQ").

Each request carries a tag frame that its reply echoes, so a late reply to a request that
timed out is recognised and dropped. ``ZMQ_IMMEDIATE`` keeps a socket unwritable until its
connection is complete: whether the daemon is reachable is read off the socket itself, with
no liveliness token (ZeroMQ has none) -- a connection that is up means "busy", one that is
down means "unreachable".

A state stream belongs to the connection that opened it, and the daemon ends it when that
connection sends nothing for the stream's ``silence_s`` (a stopped process keeps its
connection open): ``stream_states`` and ``close_stream`` go over one DEALER of their own,
shared under a lock, on which a thread sends a ``status`` a third of that apart while a
stream is open (docs/protocol.md, "ZeroMQ").
"""

from __future__ import annotations

import itertools
import logging
import math
import os
import threading
import time
from collections.abc import Callable
from typing import Any

import zmq

from galton.client.transport.base import Topic
from galton.client.transport.zmq_keys import HANDSHAKE_EVENTS, ZmqKeys, wait_for_handshake
from galton.protocol import (
    AccessDeniedError,
    DaemonUnreachableError,
    InvalidArgumentError,
    Reply,
    RequestTimeoutError,
    decode_reply,
    encode_request,
)
from galton.protocol.errors import ClientClosedError, GaltonError, brief

log = logging.getLogger("galton.client")

CONNECT_TIMEOUT_S = 1.0  # how long a new socket may take to connect before "unreachable"
SUBSCRIBER_POLL_MS = 100
HELLO_TIMEOUT_S = 10.0  # a subscription waits this long for the daemon's greeting
STREAM_OPS = frozenset({"stream_states", "close_stream"})  # sent on the streams' DEALER
KEEPALIVES_PER_SILENCE = 3  # keepalives sent within each stream's silence_s


def check_endpoint(endpoint: str) -> str:
    if endpoint.startswith(("ipc://", "tcp://")) and len(endpoint) > len("tcp://"):
        return endpoint
    raise InvalidArgumentError(
        f"{brief(endpoint)} is not a ZeroMQ endpoint: give zmq+ipc:///path/to/socket or "
        "zmq+tcp://HOST:PORT")


class ZmqTransport:
    """Requests to one daemon's ZeroMQ control endpoint."""

    kind = "zmq"

    def __init__(self, endpoint: str, connect_timeout: float = CONNECT_TIMEOUT_S,
                 keys: ZmqKeys | None = None) -> None:
        self.endpoint = check_endpoint(endpoint)
        self.keys = keys
        path = endpoint[len("ipc://"):]
        if endpoint.startswith("ipc://") and not os.path.exists(path):
            raise DaemonUnreachableError(
                f"no galton-daemon serves {endpoint}: there is no socket file at {path} "
                f"(start one with `galton-daemon --zmq {endpoint}`)")
        self.connect_timeout = connect_timeout
        self.context = zmq.Context()
        self._local = threading.local()
        self._tags = itertools.count(1)
        self._lock = threading.Lock()
        # Every thread's DEALER, held here: a thread's local storage goes with the thread, and
        # a socket collected unclosed warns (ResourceWarning); close() destroys them all.
        self._sockets: list[zmq.Socket[bytes]] = []
        self._subscriptions: list[ZmqSubscription] = []
        self._telemetry_endpoint: str | None = None
        self._keepalive = StreamKeepalive(self._connect)
        try:
            self._socket()  # fail now, as a Zenoh client does, if nothing answers there
        except (DaemonUnreachableError, AccessDeniedError, InvalidArgumentError):
            self.close()
            raise

    def _socket(self) -> zmq.Socket[bytes]:
        """This thread's DEALER (connecting it the first time)."""
        socket: zmq.Socket[bytes] | None = getattr(self._local, "socket", None)
        if socket is None:
            socket = self._connect(lambda made: setattr(self._local, "socket", made))
        return socket

    def _connect(self, keep: Callable[[zmq.Socket[bytes]], None] | None = None
                 ) -> zmq.Socket[bytes]:
        """A new DEALER, connected (or DaemonUnreachableError), held for ``close`` and
        handed to ``keep`` before the handshake is awaited (a late one may still connect)."""
        socket = self.context.socket(zmq.DEALER)
        socket.setsockopt(zmq.IMMEDIATE, 1)
        socket.setsockopt(zmq.LINGER, 0)
        if self.keys is not None:
            self.keys.apply(socket)
        monitor = socket.get_monitor_socket(HANDSHAKE_EVENTS)
        try:
            socket.connect(self.endpoint)
        except zmq.ZMQError as error:  # e.g. tcp://nohost: no port, or not a number
            socket.close(linger=0)
            monitor.close(linger=0)
            raise InvalidArgumentError(
                f"{brief(self.endpoint)} is not a ZeroMQ endpoint ZeroMQ can connect to "
                f"({error}): give zmq+ipc:///path/to/socket or zmq+tcp://HOST:PORT"
            ) from None
        with self._lock:
            self._sockets.append(socket)
        if keep is not None:
            keep(socket)
        try:
            wait_for_handshake(socket, monitor, self.endpoint, self.connect_timeout)
        finally:
            socket.disable_monitor()
            monitor.close(linger=0)
        return socket

    def _wait_connected(self, socket: zmq.Socket[bytes]) -> None:
        """Wait up to the connect timeout for a connection (or DaemonUnreachableError)."""
        if not socket.poll(int(self.connect_timeout * 1000), zmq.POLLOUT):
            raise DaemonUnreachableError(
                f"no galton-daemon answers at {self.endpoint} (start one with "
                f"`galton-daemon --zmq {self.endpoint}`)")

    def _send(self, socket: zmq.Socket[bytes], frames: list[bytes]) -> None:
        """Send at once while connected; else wait for a connection first (ZMQ_IMMEDIATE
        makes a send with no connection fail rather than queue)."""
        try:
            socket.send_multipart(frames, zmq.NOBLOCK)
        except zmq.Again:
            self._wait_connected(socket)
            socket.send_multipart(frames, zmq.NOBLOCK)

    def exchange(self, what: str, payload: bytes, timeout: float,
                 socket: zmq.Socket[bytes] | None = None) -> bytes:
        """Send one request (on ``socket``, else this thread's DEALER) and wait for its
        reply's bytes; a client closed meanwhile (by another thread) raises
        ClientClosedError."""
        try:
            return self._exchange(what, payload, timeout, socket)
        except zmq.Again:  # connected a moment ago, gone before the send
            raise DaemonUnreachableError(f"{what}: the daemon at {self.endpoint} went away "
                                         "(no connection)") from None
        except zmq.ZMQError as error:
            if self.context.closed or error.errno in (zmq.ETERM, zmq.ENOTSOCK):
                raise ClientClosedError(
                    f"{what}: the client was closed while its request waited") from None
            raise DaemonUnreachableError(f"{what}: ZeroMQ failed: {error}") from error

    def _exchange(self, what: str, payload: bytes, timeout: float,
                  socket: zmq.Socket[bytes] | None = None) -> bytes:
        socket = self._socket() if socket is None else socket
        tag = next(self._tags).to_bytes(8, "little")
        self._send(socket, [tag, payload])
        deadline = time.monotonic() + timeout
        while (remaining := deadline - time.monotonic()) > 0:
            if socket.poll(max(1, int(remaining * 1000 + 0.5))):
                frames = socket.recv_multipart()
                if len(frames) == 2 and frames[0] == tag:
                    return frames[1]
        if socket.poll(0, zmq.POLLOUT):
            raise RequestTimeoutError(
                f"{what}: the daemon at {self.endpoint} is connected but sent no reply within "
                f"{timeout:g} s (busy with a long request, or the operation needs longer: "
                "pass a longer timeout)")
        raise DaemonUnreachableError(
            f"{what}: the daemon at {self.endpoint} went away (no connection)")

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply:
        if op in STREAM_OPS:
            return self._keepalive.request(op, args, lambda socket: decode_reply(
                self.exchange(op, encode_request(op, args, client), timeout, socket)))
        return decode_reply(self.exchange(op, encode_request(op, args, client), timeout))

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        try:
            return [self.exchange(op, payload, timeout)]
        except RequestTimeoutError:
            return []

    def telemetry_endpoint(self) -> str:
        """The PUB endpoint beside our control endpoint, as ``capabilities`` names it."""
        if self._telemetry_endpoint is None:
            reply = self.request("capabilities", None, 10.0, None)
            reply.raise_for_code()
            advertised = reply.result.get("zmq") or {}
            control, telemetry = advertised.get("control", []), advertised.get("telemetry", [])
            if not telemetry:
                raise DaemonUnreachableError(
                    f"the daemon at {self.endpoint} advertises no telemetry endpoint")
            index = control.index(self.endpoint) if self.endpoint in control else 0
            self._telemetry_endpoint = str(telemetry[min(index, len(telemetry) - 1)])
        return self._telemetry_endpoint

    def subscribe(self, topic: Topic, callback: Callable[[bytes], None],
                  key: str | None = None) -> ZmqSubscription:
        """``key`` (a state stream's): only that key's messages and the greeting are
        subscribed to, not every topic, so that the daemon sends this socket no others."""
        filters = ((key.encode(), key.rsplit("/", 2)[0].encode() + b"/hello")
                   if key is not None else (b"galton/",))
        subscription = ZmqSubscription(self.context, self.telemetry_endpoint(), topic,
                                       callback, self.keys, filters)
        with self._lock:  # those undeclared since are let go
            self._subscriptions = [*(s for s in self._subscriptions if s.live), subscription]
        return subscription

    def close(self) -> None:
        """Stop the subscriptions' threads (each closes its own socket: closing it under
        its thread's poll crashed that thread), then close every other socket and the
        context."""
        self._keepalive.stop()
        with self._lock:
            subscriptions, self._subscriptions = self._subscriptions, []
        for subscription in subscriptions:
            subscription.undeclare()
        self.context.destroy(linger=0)


class StreamKeepalive:
    """The DEALER that opens and closes state streams, and the thread that keeps its
    connection heard while a stream is open: a ``status`` when nothing went for a third of
    the shortest ``silence_s`` (fire and forget: its replies are read off before the next)."""

    def __init__(self, connect: Callable[[Callable[[zmq.Socket[bytes]], None]],
                                         zmq.Socket[bytes]]) -> None:
        self._connect = connect
        self._lock = threading.Lock()  # the socket is used by one thread at a time
        self._socket: zmq.Socket[bytes] | None = None
        self._streams: set[str] = set()
        self._period = math.inf
        self._last_sent = 0.0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def request(self, op: str, args: dict[str, Any] | None,
                exchange: Callable[[zmq.Socket[bytes]], Reply]) -> Reply:
        """``stream_states`` or ``close_stream`` through ``exchange`` on the streams'
        DEALER; the streams open are counted from the replies."""
        with self._lock:
            if self._socket is None:
                self._connect(self._keep)
            assert self._socket is not None
            reply = exchange(self._socket)
            self._last_sent = time.monotonic()
            if reply.ok and op == "stream_states":
                self._streams.add(str(reply.result["stream"]))
                silence = reply.result.get("silence_s")
                if isinstance(silence, int | float) and silence > 0:
                    self._period = min(self._period, silence / KEEPALIVES_PER_SILENCE)
                    self._start()
            elif op == "close_stream" and args is not None:
                self._streams.discard(str(args.get("stream")))
        return reply

    def _keep(self, socket: zmq.Socket[bytes]) -> None:
        self._socket = socket

    def _start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="galton-zmq-keepalive",
                                            daemon=True)
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self._period):
            try:
                self._ping()
            except (zmq.ZMQError, GaltonError) as error:  # closing, or the daemon went
                log.debug("stream keepalive: %s", error)

    def _ping(self) -> None:
        with self._lock:
            socket = self._socket
            if socket is None or not self._streams or self._stop.is_set() or \
                    time.monotonic() - self._last_sent < self._period * 0.9:
                return
            while socket.poll(0):  # the replies to the last pings
                socket.recv_multipart()
            socket.send_multipart([b"", encode_request("status", None, None)], zmq.NOBLOCK)
            self._last_sent = time.monotonic()

    def stop(self) -> None:
        """Stop the thread (before the context closes its socket)."""
        self._stop.set()
        if self._thread is not None:  # a ping takes microseconds; a request holding the
            self._thread.join(1.0)  # lock ends when the context closes (the thread returns)


class ZmqSubscription:
    """A SUB socket read by a thread of its own, which calls ``callback`` per message of
    the topic (``galton/<instance>/<topic>``); ``undeclare`` stops it. It is returned once
    the daemon's "hello" has arrived: from then on nothing published is missed."""

    def __init__(self, context: zmq.Context[zmq.Socket[bytes]], endpoint: str, topic: Topic,
                 callback: Callable[[bytes], None], keys: ZmqKeys | None = None,
                 filters: tuple[bytes, ...] = (b"galton/",)) -> None:
        self._suffix = b"/" + topic.encode()
        self._callback = callback
        self._stop = threading.Event()
        self._socket = context.socket(zmq.SUB)
        self._socket.setsockopt(zmq.LINGER, 0)
        if keys is not None:
            keys.apply(self._socket)
        self._socket.connect(endpoint)
        for prefix in filters:
            self._socket.subscribe(prefix)
        self._ready = threading.Event()
        self._thread = threading.Thread(target=self._run, name="galton-zmq-sub", daemon=True)
        self._thread.start()
        if not self._ready.wait(HELLO_TIMEOUT_S):
            self.undeclare()
            raise DaemonUnreachableError(
                f"the daemon's telemetry endpoint {endpoint} did not greet this subscription "
                f"within {HELLO_TIMEOUT_S:g} s")

    def _run(self) -> None:
        socket = self._socket
        try:
            while not self._stop.is_set():
                if not socket.poll(SUBSCRIBER_POLL_MS):
                    continue
                frames = socket.recv_multipart()
                if len(frames) == 2 and frames[0].endswith(b"/hello"):
                    self._ready.set()
                elif len(frames) == 2 and frames[0].endswith(self._suffix):
                    try:
                        self._callback(frames[1])
                    except Exception:
                        log.exception("a subscription callback failed")
        except zmq.ContextTerminated:
            return
        finally:
            socket.close(linger=0)

    @property
    def live(self) -> bool:
        """Whether ``undeclare`` has not been called."""
        return not self._stop.is_set()

    def undeclare(self) -> None:
        """Stop the thread (within one poll period) and close its socket."""
        self._stop.set()
        if threading.current_thread() is not self._thread:
            self._thread.join(SUBSCRIBER_POLL_MS / 1000 * 5)
