"""Opening a Zenoh session to daemons, and turning a Zenoh get into a reply or an error."""

from __future__ import annotations

import json
import time
from collections.abc import Sequence
from typing import Any

import zenoh

from galton.protocol import (
    DEFAULT_PORT,
    DaemonUnreachableError,
    Reply,
    RequestTimeoutError,
    decode_reply,
    encode_request,
)

DEFAULT_ENDPOINT = f"tcp/127.0.0.1:{DEFAULT_PORT}"


def split_endpoints(connect: str | Sequence[str] | None) -> list[str]:
    """Accept one endpoint, a comma-separated list, or a sequence; default: loopback."""
    if connect is None:
        return [DEFAULT_ENDPOINT]
    items = [connect] if isinstance(connect, str) else list(connect)
    endpoints = [e.strip() for item in items for e in item.split(",") if e.strip()]
    return endpoints or [DEFAULT_ENDPOINT]


def open_session(connect: str | Sequence[str] | None = None,
                 config_file: str | None = None) -> zenoh.Session:
    """A session to the given endpoints, multicast scouting off.

    One endpoint: a Zenoh client (it reaches every daemon meshed with that one). Several: a
    non-listening peer, since a Zenoh client connects to the first endpoint only.
    """
    endpoints = split_endpoints(connect)
    config = zenoh.Config.from_file(config_file) if config_file else zenoh.Config()
    if config_file is None:
        config.insert_json5("mode", json.dumps("client" if len(endpoints) == 1 else "peer"))
        config.insert_json5("scouting/multicast/enabled", "false")
        if len(endpoints) > 1:
            config.insert_json5("listen/endpoints", "[]")
    config.insert_json5("connect/endpoints", json.dumps(endpoints))
    try:
        return zenoh.open(config)
    except zenoh.ZError as error:
        raise DaemonUnreachableError(
            f"no Zenoh peer answers at {', '.join(endpoints)}: is galton-daemon running there? "
            f"(start one with `galton-daemon --listen {endpoints[0]}`) [{error}]") from error


def query(session: zenoh.Session, key: str, op: str, args: dict[str, Any] | None,
          timeout: float, client: str | None = None) -> Reply:
    """Send one request and return the daemon's reply; no answer is an error, never empty."""
    started = time.monotonic()
    replies = session.get(key, payload=encode_request(op, args, client), timeout=timeout)
    for answer in replies:
        if answer.ok is not None:
            return decode_reply(answer.ok.payload.to_bytes())
    elapsed = time.monotonic() - started
    if elapsed >= 0.9 * timeout:
        raise RequestTimeoutError(
            f"{op}: no reply within {timeout:g} s from {key.rsplit('/@', 1)[0]}; pass a "
            "longer timeout for long operations")
    raise DaemonUnreachableError(
        f"{op}: no daemon serves {key.rsplit('/@', 1)[0]} (not running, or another instance "
        "name: `galton-client ls` lists them)")
