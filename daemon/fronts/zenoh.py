"""The Zenoh front: the session, the control queryable, the publishers, the daemon's
liveliness token, and the clients' tokens it watches (docs/protocol.md).

A query becomes a ``Call`` handed to the core's call interface; its reply goes back on the
query. A client whose token vanishes is reported to the core (its step job and lease end).
The ROS 2 front (daemon/fronts/ros2/) serves on this front's session.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import zenoh

from galton.daemon.access.zenoh_security import remove_private_files
from galton.daemon.core.calls import Call, CallPort
from galton.daemon.fronts.base import EVENTS, TELEMETRY, Front
from galton.daemon.fronts.memory import after_request_of
from galton.daemon.fronts.stream_sender import SampleSender
from galton.daemon.fronts.zenoh_config import file_says, listen_endpoints, merge
from galton.protocol import Keys
from galton.protocol.envelope import is_client_id
from galton.protocol.keys import (
    CLIENTS_PATTERN,
    client_from_token_key,
    client_token_key,
    op_from_control_key,
)

CLIENT_TOKEN_TIMEOUT_S = 1.0


def merged_config(base: zenoh.Config, listen: list[str], connect: list[str], multicast: bool,
                  security: dict[str, Any]) -> zenoh.Config:
    """``base`` (the --zenoh-config file, or Zenoh's defaults) with the options merged in by
    the rules of fronts/zenoh_config.py."""
    for key, value in merge(file_says(base), listen, connect, multicast, security).items():
        base.insert_json5(key, json.dumps(value))
    return base


class ZenohFront(Front):
    """The daemon's Zenoh side, as a ``Front`` (daemon/fronts/base.py)."""

    def __init__(self, config: zenoh.Config, instance: str) -> None:
        self.keys = Keys(instance)
        self.listening = listen_endpoints(config)  # as configured, for the ready line
        try:
            self.session = zenoh.open(config)
        finally:
            remove_private_files()  # the usrpwd dictionary: Zenoh has read it
        self._telemetry_pub = self.session.declare_publisher(
            self.keys.telemetry, congestion_control=zenoh.CongestionControl.DROP)
        self._events_pub = self.session.declare_publisher(self.keys.events)
        # A state stream's samples are put off the physics thread (stream_sender.py).
        self._samples = SampleSender(self._put_sample)
        self._core: CallPort | None = None
        self._queryable: Any = None
        self._token: Any = None
        self._clients: Any = None
        # Client ids whose liveliness token this front has seen come and not go (updated on
        # Zenoh's thread; a set's add and discard are atomic under the GIL).
        self._live_clients: set[str] = set()

    def open(self, core: CallPort) -> None:
        """Declare the control queryable and the liveliness token: clients can reach us.
        Watch the clients' tokens: a step job whose client vanishes ends (docs/protocol.md)."""
        self._core = core
        self._clients = self.session.liveliness().declare_subscriber(
            CLIENTS_PATTERN, self._on_client_token, history=True)
        self._queryable = self.session.declare_queryable(self.keys.control_all, self._on_query)
        self._token = self.session.liveliness().declare_token(self.keys.alive)

    def client_alive(self, client: str) -> bool | None:
        """Whether the client's liveliness token is there: seen by the subscriber (no wait),
        else asked once (a token declared a moment ago may not have reached us yet; the get
        holds the physics thread, under a millisecond on loopback). None for a name that is
        no client id (another front's client, e.g. a ZeroMQ connection): not asked."""
        if not is_client_id(client):  # another front's client, whatever tokens say
            return None
        if client in self._live_clients:
            return True
        replies = self.session.liveliness().get(client_token_key(client),
                                                timeout=CLIENT_TOKEN_TIMEOUT_S)
        return any(reply.ok is not None for reply in replies)

    def _on_client_token(self, sample: zenoh.Sample) -> None:
        client = client_from_token_key(str(sample.key_expr))
        if client is None or not is_client_id(client):  # no ZeroMQ connection's name: its
            return  # going is its own front's to say
        if sample.kind == zenoh.SampleKind.PUT:
            self._live_clients.add(client)
        else:
            self._live_clients.discard(client)
            if self._core is not None:
                self._core.lose_client(client)

    def _on_query(self, query: zenoh.Query) -> None:
        op = op_from_control_key(str(query.key_expr))
        payload = query.payload.to_bytes() if query.payload is not None else b""
        after_request_of(len(payload))  # a big one's buffers go back to the OS after it
        assert self._core is not None  # the queryable is declared in open()
        self._core.dispatch(Call(op, payload, _responder(query)))

    def publish(self, topic: str, data: bytes) -> None:
        """Telemetry and state streams are dropped rather than queued when the network is
        congested; events are not. A state stream's sample is handed to the sender's
        thread: a 60 kB put would cost the physics thread as much as reading the poses."""
        if topic == TELEMETRY:
            self._telemetry_pub.put(data)
        elif topic == EVENTS:
            self._events_pub.put(data)
        else:
            self._samples.send(topic, data)

    def _put_sample(self, topic: str, data: bytes) -> None:
        self.session.put(f"{self.keys.prefix}/{topic}", data,
                         congestion_control=zenoh.CongestionControl.DROP)

    def ready_words(self) -> str:
        """Where it listens (clients find it by its key expressions: nothing advertised)."""
        return f"listen={','.join(self.listening)}"

    def withdraw(self) -> None:
        """Withdraw the liveliness token: clients see the daemon go before it closes."""
        if self._token is not None:
            self._token.undeclare()
            self._token = None

    def close(self) -> None:
        self._samples.close()  # the samples handed over before this go out first
        if self._queryable is not None:
            self._queryable.undeclare()
        if self._clients is not None:
            self._clients.undeclare()
        self.session.close()


def _responder(query: zenoh.Query) -> Callable[[bytes], None]:
    def respond(data: bytes) -> None:
        try:
            query.reply(query.key_expr, data)
        finally:
            query.drop()
    return respond

