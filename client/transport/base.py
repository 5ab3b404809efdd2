"""How a Client reaches its daemon: Zenoh (any host, discovery, many daemons) or ZeroMQ
(one daemon's own endpoint, the same-host fast path). Both carry the same envelope and
replies; ``transport_for`` picks one from the endpoint a user gives.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, Protocol

import zenoh

from galton.client.transport.credentials import Credentials
from galton.client.transport.session import (
    Declared,
    close_session,
    open_session,
    query,
    split_endpoints,
    undeclare,
)
from galton.protocol import DaemonUnreachableError, InvalidArgumentError, Keys, Reply
from galton.protocol.errors import ClientClosedError, brief
from galton.protocol.keys import client_token_key

if TYPE_CHECKING:  # ZeroMQ is imported only for a zmq+ endpoint
    from galton.client.transport.zmq_keys import ZmqKeys

ZMQ_SCHEME = "zmq+"
Topic = str  # "telemetry", "events", or a state stream's "states/<id>"


class Transport(Protocol):
    """What the SDK needs of a transport."""

    kind: str

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply: ...

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        """Every reply to a request sent as these exact bytes (tests and the fuzzer)."""
        ...

    def subscribe(self, topic: Topic, callback: Callable[[bytes], None],
                  key: str | None = None) -> Declared:
        """Subscribe to a topic of the instance; ``key``: the whole key a daemon named (a
        state stream's), else the topic under this client's instance."""
        ...

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


def transport_for(keys: Keys, client_id: str, connect: str | Sequence[str] | None,
                  session: zenoh.Session | None = None, config_file: str | None = None,
                  credentials: Credentials | None = None,
                  zmq_keys: ZmqKeys | None = None) -> Transport:
    """ZeroMQ for a ``zmq+ipc://`` or ``zmq+tcp://`` endpoint (CURVE keys from ``zmq_keys``,
    else GALTON_ZMQ_KEY and GALTON_ZMQ_SERVER_KEY), else Zenoh. pyzmq is imported only for
    the first (a command line that asks one Zenoh daemon starts without it)."""
    endpoint = zmq_endpoint(connect)
    if endpoint is None:
        if zmq_keys is not None:
            raise InvalidArgumentError("ZeroMQ keys are for a zmq+ endpoint, not Zenoh")
        return ZenohTransport(keys, client_id, session, connect, config_file, credentials)
    if session is not None or config_file is not None or credentials is not None:
        raise InvalidArgumentError(
            "a ZeroMQ endpoint takes no Zenoh session, config file or credentials: its "
            "security is CURVE keys (zmq_keys)")
    from galton.client.transport.zmq import ZmqTransport
    from galton.client.transport.zmq_keys import ZmqKeys
    return ZmqTransport(endpoint, keys=zmq_keys or ZmqKeys.from_env())


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

    def request(self, op: str, args: dict[str, Any] | None, timeout: float,
                client: str | None) -> Reply:
        """One get on the operation's key (a declared querier was tried: 1 % faster, and it
        ended gets in flight when a client sharing the session closed; PERFORMANCE.md)."""
        try:
            return query(self.session, self.keys, op, args, timeout, client)
        except zenoh.ZError as error:
            if self.session.is_closed():  # closed by another thread while this one waited
                raise ClientClosedError(
                    f"{op}: the client was closed while its request waited") from None
            raise DaemonUnreachableError(f"{op}: Zenoh failed: {error}") from error

    def send_raw(self, op: str, payload: bytes, timeout: float) -> list[bytes]:
        replies = self.session.get(self.keys.control(op), payload=payload, timeout=timeout)
        return [r.ok.payload.to_bytes() if r.ok is not None else b"" for r in replies]

    def subscribe(self, topic: Topic, callback: Callable[[bytes], None],
                  key: str | None = None) -> Declared:
        if key is None:
            key = f"{self.keys.prefix}/{topic}"

        def on_sample(sample: zenoh.Sample) -> None:
            callback(sample.payload.to_bytes())
        subscriber: Declared = self.session.declare_subscriber(key, on_sample)
        return subscriber

    def close(self) -> None:
        if self._token is not None:
            undeclare(self._token)
            self._token = None
        if self.own_session:
            close_session(self.session)
