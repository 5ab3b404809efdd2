"""Opening a Zenoh session to daemons, and turning a Zenoh get into a reply or an error.

A get that brings no reply is never an empty answer: the daemon's liveliness token decides
what it was. A token there means the daemon is alive but did not answer in time (busy:
RequestTimeoutError), or refused at once (access control: AccessDeniedError); no token
means no daemon serves that instance (DaemonUnreachableError).
"""

from __future__ import annotations

import json
import math
import numbers
import time
from collections.abc import Iterable, Sequence
from typing import Any, Protocol

import zenoh

from galton.client.transport.access import access_denied, refused_at_once, session_refused
from galton.client.transport.credentials import Credentials
from galton.protocol import (
    DEFAULT_PORT,
    DaemonUnreachableError,
    InvalidArgumentError,
    Keys,
    Reply,
    RequestTimeoutError,
    decode_reply,
    encode_request,
)
from galton.protocol.errors import brief

DEFAULT_ENDPOINT = f"tcp/127.0.0.1:{DEFAULT_PORT}"
# How long a liveliness get may take to say whether a silent daemon is there. It answers
# in well under a millisecond on loopback whether or not the token exists.
LIVELINESS_TIMEOUT_S = 1.0
# How long a get that ended early is watched before it counts as refused: a daemon killed
# mid-request ends the get at once too, and its token takes a moment to vanish.
DEATH_GRACE_S = 0.3


class Declared(Protocol):
    """A Zenoh declaration (token, subscriber); the stubs leave ``undeclare`` untyped."""

    def undeclare(self) -> None: ...


class Closable(Protocol):
    """A Zenoh session, as far as closing it goes (``close`` is untyped in the stubs)."""

    def close(self) -> None: ...


def undeclare(declared: Declared) -> None:
    declared.undeclare()


def close_session(session: Closable) -> None:
    session.close()


def checked_timeout(timeout: object, where: str = "timeout") -> float:
    """A timeout in seconds: a finite number above 0. Zero used to mean "the default",
    silently; a caller who wants the default passes None instead."""
    if isinstance(timeout, bool) or not isinstance(timeout, numbers.Real) or (
            not math.isfinite(timeout) or timeout <= 0):
        raise InvalidArgumentError(
            f"{where} must be a finite number of seconds above 0, got {brief(timeout)}; "
            "pass None for the operation's default")
    return float(timeout)


def split_endpoints(connect: str | Sequence[str] | None) -> list[str]:
    """Accept one endpoint, a comma-separated list, or a sequence; default: loopback."""
    if connect is None:
        return [DEFAULT_ENDPOINT]
    items = [connect] if isinstance(connect, str) else list(connect)
    endpoints = [e.strip() for item in items for e in item.split(",") if e.strip()]
    return endpoints or [DEFAULT_ENDPOINT]


def open_session(connect: str | Sequence[str] | None = None,
                 config_file: str | None = None,
                 credentials: Credentials | None = None) -> zenoh.Session:
    """A session to the given endpoints, multicast scouting off, with these credentials.

    One endpoint: a Zenoh client (it reaches every daemon meshed with that one). Several: a
    non-listening peer, since a Zenoh client connects to the first endpoint only. With one
    endpoint, a daemon that refuses the session raises AccessDeniedError (transport/access.py);
    a peer session opens whatever its endpoints do, and a refusing daemon is never seen.
    """
    endpoints = split_endpoints(connect)
    zmq = [endpoint for endpoint in endpoints if endpoint.startswith("zmq+")]
    if zmq:
        raise InvalidArgumentError(
            f"{zmq[0]} is a ZeroMQ endpoint, which reaches one daemon's requests only: "
            "finding daemons and sharing a session need Zenoh (tcp/HOST:PORT)")
    config = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    if config_file is None:
        config.insert_json5("mode", json.dumps("client" if len(endpoints) == 1 else "peer"))
        config.insert_json5("scouting/multicast/enabled", "false")
        if len(endpoints) > 1:
            config.insert_json5("listen/endpoints", "[]")
    config.insert_json5("connect/endpoints", json.dumps(endpoints))
    for key, value in (credentials.zenoh_settings() if credentials else {}).items():
        config.insert_json5(key, json.dumps(value))
    try:
        return zenoh.open(config)
    except zenoh.ZError as error:
        raise session_refused(endpoints, credentials, error) from error


def daemon_alive(session: zenoh.Session, keys: Keys,
                 timeout: float = LIVELINESS_TIMEOUT_S) -> bool:
    """Whether the instance's liveliness token is visible from this session now."""
    replies = session.liveliness().get(keys.alive, timeout=timeout)
    return any(reply.ok is not None for reply in replies)


def query(session: zenoh.Session, keys: Keys, op: str, args: dict[str, Any] | None,
          timeout: float, client: str | None = None) -> Reply:
    """Send one request to an instance and return its reply; no reply raises
    RequestTimeoutError if the daemon is alive, else DaemonUnreachableError."""
    wait = checked_timeout(timeout)
    replies = session.get(keys.control(op), payload=encode_request(op, args, client),
                          timeout=wait)
    return first_reply(replies, session, keys, op, wait)


def first_reply(replies: Iterable[zenoh.Reply], session: zenoh.Session, keys: Keys, op: str,
                wait: float) -> Reply:
    """The first reply of a get, or the error its silence means (see the module's doc)."""
    started = time.monotonic()
    for answer in replies:
        if answer.ok is not None:
            return decode_reply(answer.ok.payload.to_bytes())
    if daemon_alive(session, keys):
        if refused_at_once(time.monotonic() - started, wait):
            if not stays_alive(session, keys, DEATH_GRACE_S):
                raise unreachable(op, keys.instance)
            raise access_denied(op, keys.instance)
        raise RequestTimeoutError(
            f"{op}: daemon {keys.instance!r} is alive but sent no reply within {wait:g} s "
            "(busy with a long request, or the operation needs longer: pass a longer "
            "timeout)")
    raise unreachable(op, keys.instance)


def stays_alive(session: zenoh.Session, keys: Keys, grace_s: float) -> bool:
    """Whether the instance's token stays visible for grace_s (looked at again and again:
    each look is a liveliness round trip); False as soon as it is gone."""
    until = time.monotonic() + grace_s
    while time.monotonic() < until:
        if not daemon_alive(session, keys):
            return False
    return True


def unreachable(op: str, instance: str) -> DaemonUnreachableError:
    return DaemonUnreachableError(
        f"{op}: no daemon serves instance {instance!r} (not running, or another "
        "instance name: `galton-client daemons` lists them)")
