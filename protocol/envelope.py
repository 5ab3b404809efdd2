"""The versioned msgpack request/reply envelope carried by Zenoh queries."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import msgpack

from galton.protocol.codes import ResultCode
from galton.protocol.errors import (
    InvalidArgumentError,
    MalformedRequestError,
    RemoteError,
    ResourceLimitError,
    UnsupportedVersionError,
    brief,
    error_for_code,
)

PROTOCOL_VERSION = 1


@dataclass
class Request:
    """One operation call: ``op`` names it, ``args`` holds its fields; ``client`` is the
    sender's id (its liveliness token's last chunk), so a long step can be tied to it."""

    op: str
    args: dict[str, Any] = field(default_factory=dict)
    version: int = PROTOCOL_VERSION
    client: str | None = None


@dataclass(frozen=True)
class DecodeLimits:
    """What a request may hold before anything reads it (the daemon's limits)."""

    max_bytes: int = 16 * 1024 * 1024
    max_depth: int = 16
    max_string: int = 4096
    long_text_keys: frozenset[str] = frozenset()  # top-level args exempt from max_string


NO_LIMITS = DecodeLimits(max_bytes=2**62, max_depth=10_000, max_string=2**62)
CLIENT_ID_LENGTH = 64


@dataclass
class Reply:
    """The answer to one request, stamped with the step and sim time it took effect at."""

    code: ResultCode
    message: str = ""
    result: dict[str, Any] = field(default_factory=dict)
    step: int = 0
    sim_time: float = 0.0
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.code == ResultCode.OK

    def raise_for_code(self) -> None:
        """Raise the exception this reply's code stands for, if it is a failure."""
        if not self.ok:
            raise error_for_code(self.code, self.message, self.details)


def encode_request(op: str, args: dict[str, Any] | None = None,
                   client: str | None = None) -> bytes:
    body: dict[str, Any] = {"v": PROTOCOL_VERSION, "op": op, "args": args or {}}
    if client is not None:
        body["client"] = client
    data: bytes = msgpack.packb(body, use_bin_type=True)
    return data


def decode_request(payload: bytes, op_from_key: str | None = None,
                   limits: DecodeLimits = NO_LIMITS) -> Request:
    """Parse a request, raising MalformedRequest, UnsupportedVersion or ResourceLimit with
    the reason. Size is checked before decoding; depth and strings before any field is read."""
    if len(payload) > limits.max_bytes:
        raise ResourceLimitError(
            f"the request is {len(payload)} bytes; this daemon takes at most "
            f"{limits.max_bytes}", {"limit": "max_request_bytes", "max": limits.max_bytes})
    try:
        body = msgpack.unpackb(payload, raw=False, strict_map_key=True)
    except msgpack.StackError as exc:  # deeper than msgpack's own stack (about 1,000)
        raise _too_deep(limits) from exc
    except Exception as exc:
        raise MalformedRequestError(f"payload is not valid msgpack: {brief(str(exc))}") from exc
    if not isinstance(body, dict):
        raise MalformedRequestError(
            f"request must be a msgpack map with 'v', 'op', 'args', got {type(body).__name__}"
        )
    check_shape(body, limits)
    version = body.get("v")
    if version != PROTOCOL_VERSION:
        raise UnsupportedVersionError(
            f"protocol version {brief(version)} is not supported; this daemon speaks "
            f"v{PROTOCOL_VERSION} (every request carries 'v': {PROTOCOL_VERSION})",
            {"supported": [PROTOCOL_VERSION]},
        )
    op = body.get("op", op_from_key)
    if not isinstance(op, str):
        raise MalformedRequestError(f"'op' must be a string, got {type(op).__name__}")
    if op_from_key is not None and op != op_from_key:
        raise MalformedRequestError(
            f"'op' is {brief(op)} but the key names {brief(op_from_key)}: send each request "
            "to its own operation's key")
    unknown = set(body) - ENVELOPE_FIELDS
    if unknown:
        raise MalformedRequestError(
            f"the envelope has unknown fields {brief(sorted(map(str, unknown)))}; it holds "
            f"{', '.join(sorted(ENVELOPE_FIELDS))}")
    args = body.get("args", {})
    if args is None:
        args = {}
    if not isinstance(args, dict):
        raise MalformedRequestError(f"'args' must be a map, got {type(args).__name__}")
    return Request(op=op, args=args, version=version, client=_client_id(body.get("client")))


ENVELOPE_FIELDS = frozenset({"v", "op", "args", "client"})


# Characters a client id may not hold: it names one liveliness token, one key chunk
# galton/_clients/<id>, so no '/', no key-expression wildcard ('*', '**', '$*'), nothing Zenoh
# refuses in a key ('?', '#'), no space; and it may not start with '@' (a verbatim chunk).
NOT_IN_CLIENT_ID = frozenset("/*$?#")


def is_client_id(value: str) -> bool:
    """Whether ``value`` may be a client id: a name no id can have is no client's (a
    ZeroMQ connection's name starts with '@', so that no client can pass for one)."""
    return 0 < len(value) <= CLIENT_ID_LENGTH and not NOT_IN_CLIENT_ID.intersection(value) \
        and not value.startswith("@") and value.isprintable() \
        and not any(c.isspace() for c in value)


def _client_id(value: Any) -> str | None:
    """The envelope's client id, an id (issue 46): "*" once opened a stream every client
    would keep alive."""
    if value is None:
        return None
    if not isinstance(value, str) or not 0 < len(value) <= CLIENT_ID_LENGTH:
        raise MalformedRequestError(
            f"'client' must be a string of 1-{CLIENT_ID_LENGTH} characters, got {brief(value)}")
    if not is_client_id(value):
        raise InvalidArgumentError(
            f"'client' {brief(value)} is not a client id: it names one liveliness token "
            "galton/_clients/<id>, so it holds no '/', '*', '$', '?', '#' or space and does "
            "not start with '@'")
    return value


def check_shape(body: dict[str, Any], limits: DecodeLimits) -> None:
    """Refuse a request nested deeper than ``max_depth`` or holding a string longer than
    ``max_string`` (but the long-text args); iterative, so no depth can overflow it."""
    args = body.get("args")
    stack: list[tuple[Any, int, bool]] = [(body, 1, False)]
    while stack:
        value, depth, exempt = stack.pop()
        if isinstance(value, dict | list):
            if depth > limits.max_depth:
                raise _too_deep(limits)
            if isinstance(value, dict):
                for key, item in value.items():
                    _check_string(key, limits, False)
                    stack.append((item, depth + 1,
                                  value is args and key in limits.long_text_keys))
            else:
                stack.extend((item, depth + 1, False) for item in value)
        else:
            _check_string(value, limits, exempt)


def _too_deep(limits: DecodeLimits) -> ResourceLimitError:
    return ResourceLimitError(
        f"the request nests maps and lists deeper than {limits.max_depth} levels",
        {"limit": "max_depth", "max": limits.max_depth})


def _check_string(value: Any, limits: DecodeLimits, exempt: bool) -> None:
    if isinstance(value, str) and not exempt and len(value) > limits.max_string:
        raise ResourceLimitError(
            f"a string of the request holds {len(value)} characters ({brief(value, 40)}); "
            f"at most {limits.max_string}", {"limit": "max_string_bytes",
                                             "max": limits.max_string})


def encode_reply(reply: Reply) -> bytes:
    data: bytes = msgpack.packb(
        {
            "v": PROTOCOL_VERSION,
            "code": int(reply.code),
            "code_name": reply.code.name,
            "message": reply.message,
            "result": reply.result,
            "step": reply.step,
            "sim_time": reply.sim_time,
            "details": reply.details,
        },
        use_bin_type=True,
    )
    return data


MAX_MESSAGE = 2000  # characters of an error message; the values it quotes are brief()


def error_reply(error: RemoteError, step: int = 0, sim_time: float = 0.0) -> Reply:
    message = error.message if len(error.message) <= MAX_MESSAGE else (
        error.message[:MAX_MESSAGE] + "...")
    return Reply(code=error.code, message=message, step=step, sim_time=sim_time,
                 details=error.details)


def decode_reply(payload: bytes) -> Reply:
    """Parse a daemon's reply; a reply that is not one raises MalformedRequestError."""
    try:
        body = msgpack.unpackb(payload, raw=False)
        return Reply(
            code=ResultCode(body["code"]),
            message=body.get("message", ""),
            result=body.get("result") or {},
            step=body.get("step", 0),
            sim_time=body.get("sim_time", 0.0),
            details=body.get("details") or {},
        )
    except Exception as exc:
        raise MalformedRequestError(f"daemon sent an unreadable reply: {exc}") from exc


