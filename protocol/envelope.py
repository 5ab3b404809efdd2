"""The versioned msgpack request/reply envelope carried by Zenoh queries."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import msgpack

from galton.protocol.codes import ResultCode
from galton.protocol.errors import (
    MalformedRequestError,
    RemoteError,
    UnsupportedVersionError,
    error_for_code,
)

PROTOCOL_VERSION = 1


@dataclass
class Request:
    """One operation call: ``op`` names it, ``args`` holds its fields."""

    op: str
    args: dict[str, Any] = field(default_factory=dict)
    version: int = PROTOCOL_VERSION


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


def encode_request(op: str, args: dict[str, Any] | None = None) -> bytes:
    return msgpack.packb({"v": PROTOCOL_VERSION, "op": op, "args": args or {}}, use_bin_type=True)


def decode_request(payload: bytes, op_from_key: str | None = None) -> Request:
    """Parse a request, raising MalformedRequest or UnsupportedVersion with the reason."""
    try:
        body = msgpack.unpackb(payload, raw=False, strict_map_key=True)
    except Exception as exc:
        raise MalformedRequestError(f"payload is not valid msgpack: {exc}") from exc
    if not isinstance(body, dict):
        raise MalformedRequestError(
            f"request must be a msgpack map with 'v', 'op', 'args', got {type(body).__name__}"
        )
    version = body.get("v")
    if version != PROTOCOL_VERSION:
        raise UnsupportedVersionError(
            f"protocol version {version!r} is not supported; this daemon speaks "
            f"v{PROTOCOL_VERSION}",
            {"supported": [PROTOCOL_VERSION]},
        )
    op = body.get("op", op_from_key)
    if not isinstance(op, str):
        raise MalformedRequestError(f"'op' must be a string, got {type(op).__name__}")
    if op_from_key is not None and op != op_from_key:
        raise MalformedRequestError(f"'op' is {op!r} but the key names {op_from_key!r}")
    args = body.get("args", {})
    if args is None:
        args = {}
    if not isinstance(args, dict):
        raise MalformedRequestError(f"'args' must be a map, got {type(args).__name__}")
    return Request(op=op, args=args, version=version)


def encode_reply(reply: Reply) -> bytes:
    return msgpack.packb(
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


def error_reply(error: RemoteError, step: int = 0, sim_time: float = 0.0) -> Reply:
    return Reply(
        code=error.code, message=error.message, step=step, sim_time=sim_time, details=error.details
    )


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


