"""How a Client reaches its daemon: Zenoh (any host, discovery, many daemons) or ZeroMQ
(one daemon's own endpoint, the same-host fast path). Both carry the same envelope and
replies; ``transport_for`` picks one from the endpoint a user gives.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any, Protocol

import zenoh

from galton.client.credentials import Credentials
from galton.client.session import (
    Declared,
    checked_timeout,
    close_session,
    first_reply,
    open_session,
    split_endpoints,
    undeclare,
)
from galton.protocol import InvalidArgumentError, Keys, Reply, encode_request
from galton.protocol.errors import brief
from galton.protocol.keys import client_token_key

ZMQ_SCHEME = "zmq+"
MAX_QUERIERS = 64
Topic = str  # "telemetry" or "events"


class Transport(Protocol):
    """What the SDK needs of a transport."""

    kind: str

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply: ...

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        """Every reply to a request sent as these exact bytes (tests and the fuzzer)."""
        ...

    def subscribe(self, topic: Topic, callback: Callable[[bytes], None]) -> Declared: ...

    def close(self) -> None: ...


def zmq_endpoint(connect: str | Sequence[str] | None) -> str | None:
    """The ZeroMQ endpoint named by ``zmq+ipc://...`` or ``zmq+tcp://...`` (alone, or as
    the one item of a list), else None: a Zenoh endpoint list."""
    items = split_endpoints(connect) if connect is not None else []
    wanted = [item for item in items if item.startswith(ZMQ_SCHEME)]
    if not wanted:
        return None
    if len(items) > 1:
        raise InvalidArgumentError(
            f"a ZeroMQ endpoint names one daemon: give it alone, not with {brief(items)}")
    return wanted[0][len(ZMQ_SCHEME):]


class ZenohTransport:
    """Requests as Zenoh gets on the instance's control keys; this client's liveliness
    token lets the daemon end a step job whose client has gone."""

    kind = "zenoh"

    def __init__(self, keys: Keys, client_id: str, session: zenoh.Session | None = None,
                 connect: str | Sequence[str] | None = None,
                 config_file: str | None = None,
                 credentials: Credentials | None = None) -> None:
        self.keys = keys
        self.own_session = session is None
        self.session = (session if session is not None else
                        open_session(connect, config_file, credentials))
        self._token: Declared | None = self.session.liveliness().declare_token(
            client_token_key(client_id))
        self._queriers: dict[tuple[str, float], zenoh.Querier] = {}
        self._lock = threading.Lock()

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply:
        """A get through a querier declared once per operation and timeout: it skips the
        key-expression work a plain session.get does on every call."""
        wait = checked_timeout(timeout)
        payload = encode_request(op, args, client)
        querier = self._queriers.get((op, wait)) or self._declare_querier(op, wait)
        replies = (querier.get(payload=payload) if querier is not None else
                   self.session.get(self.keys.control(op), payload=payload, timeout=wait))
        return first_reply(replies, self.session, self.keys, op, wait)

    def _declare_querier(self, op: str, wait: float) -> zenoh.Querier | None:
        """A querier for this operation and timeout, kept for the session's life; None past
        MAX_QUERIERS (a caller passing ever-new timeouts gets plain gets)."""
        with self._lock:
            querier = self._queriers.get((op, wait))
            if querier is None and len(self._queriers) < MAX_QUERIERS:
                querier = self.session.declare_querier(self.keys.control(op), timeout=wait)
                self._queriers[(op, wait)] = querier
            return querier

    def _undeclare_queriers(self) -> None:
        with self._lock:
            for querier in self._queriers.values():
                undeclare(querier)
            self._queriers.clear()

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        replies = self.session.get(self.keys.control(op), payload=payload, timeout=timeout)
        return [r.ok.payload.to_bytes() if r.ok is not None else b"" for r in replies]

    def subscribe(self, topic: Topic, callback: Callable[[bytes], None]) -> Declared:
        key = self.keys.telemetry if topic == "telemetry" else self.keys.events

        def on_sample(sample: zenoh.Sample) -> None:
            callback(sample.payload.to_bytes())
        subscriber: Declared = self.session.declare_subscriber(key, on_sample)
        return subscriber

    def close(self) -> None:
        self._undeclare_queriers()
        if self._token is not None:
            undeclare(self._token)
            self._token = None
        if self.own_session:
            close_session(self.session)
