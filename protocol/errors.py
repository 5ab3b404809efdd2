"""The one exception tree of galton-bridge; wire result codes map onto it one to one.

::

    GaltonError
    ├── RemoteError                  a reply carried a failure code (``.code``)
    │   ├── NotFoundError            NOT_FOUND: no entity / world of that name
    │   ├── IncorrectStateError      INCORRECT_STATE: not allowed in the current sim state
    │   ├── FeatureUnsupportedError  FEATURE_UNSUPPORTED: this engine cannot do it
    │   ├── OperationFailedError     OPERATION_FAILED: the engine failed or was interrupted
    │   ├── InvalidArgumentError     INVALID_ARGUMENT: a field has a wrong type or value
    │   │   ├── MalformedRequestError    MALFORMED_REQUEST: not a msgpack request envelope
    │   │   └── UnknownOperationError    UNKNOWN_OPERATION: no such operation
    │   ├── NameNotUniqueError       NAME_NOT_UNIQUE: an entity of that name exists
    │   ├── UnsupportedVersionError  UNSUPPORTED_VERSION: protocol version mismatch
    │   ├── PhysicsError             PHYSICS_ERROR: the state diverged (NaN, infinite, absurd)
    │   ├── ResourceLimitError       RESOURCE_LIMIT: the request is over one of the daemon's limits
    │   ├── ControlHeldError         CONTROL_HELD: another client holds control (take_control)
    │   └── RoleDeniedError          ACCESS_DENIED: this client's role may not ask that (the
    │                                ZeroMQ front answers it; also an AccessDeniedError)
    ├── DaemonUnreachableError       no daemon answered (client side only)
    ├── RequestTimeoutError          a daemon exists but did not answer in time (client side)
    ├── AccessDeniedError            a daemon is there but refuses this client: no or wrong
    │                                credentials, or a role without that right (client side)
    ├── ClientClosedError            the SDK Client was closed before this call (client side)
    └── EngineCheckError             an engine breaks the engine contract
                                     (galton.daemon.engines.check; CheckFailedError and
                                     CheckSkippedError report one check each)
"""

from __future__ import annotations

import difflib
import reprlib
from collections.abc import Iterable, Sequence
from typing import Any

from galton.protocol.codes import ResultCode


class GaltonError(Exception):
    """Root of every error raised by galton-bridge."""


class RemoteError(GaltonError):
    """A request failed; ``code`` is the wire result code that says why."""

    code: ResultCode = ResultCode.OPERATION_FAILED

    def __init__(self, message: str, details: dict[str, Any] | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.details = details or {}


class NotFoundError(RemoteError):
    code = ResultCode.NOT_FOUND


class IncorrectStateError(RemoteError):
    code = ResultCode.INCORRECT_STATE


class FeatureUnsupportedError(RemoteError):
    code = ResultCode.FEATURE_UNSUPPORTED


class OperationFailedError(RemoteError):
    code = ResultCode.OPERATION_FAILED


class InvalidArgumentError(RemoteError):
    code = ResultCode.INVALID_ARGUMENT


class MalformedRequestError(InvalidArgumentError):
    code = ResultCode.MALFORMED_REQUEST


class UnknownOperationError(InvalidArgumentError):
    code = ResultCode.UNKNOWN_OPERATION


class NameNotUniqueError(RemoteError):
    code = ResultCode.NAME_NOT_UNIQUE


class UnsupportedVersionError(RemoteError):
    code = ResultCode.UNSUPPORTED_VERSION


class PhysicsError(RemoteError):
    code = ResultCode.PHYSICS_ERROR


class ResourceLimitError(RemoteError):
    code = ResultCode.RESOURCE_LIMIT


class ControlHeldError(RemoteError):
    """Another client holds the daemon's control lease (``details["controller"]``): only
    its holder may change the world until it releases control or disappears."""

    code = ResultCode.CONTROL_HELD


class DaemonUnreachableError(GaltonError):
    """No daemon answered at the address or instance asked for."""


class RequestTimeoutError(GaltonError):
    """A daemon is there but did not answer within the caller's timeout."""


class AccessDeniedError(GaltonError):
    """A daemon is there but refuses this client: its session was refused (no, wrong or
    unknown credentials; a certificate of another CA), or its role may not ask this
    operation. Zenoh drops such requests without a word, so this is decided on the client
    side (docs/SECURITY.md)."""


class RoleDeniedError(RemoteError, AccessDeniedError):
    """The daemon refused a request its sender's role may not ask (a viewer's spawn over
    ZeroMQ): a reply with ACCESS_DENIED. Over Zenoh such a request never reaches the daemon,
    and the client decides AccessDeniedError itself."""

    code = ResultCode.ACCESS_DENIED


class ClientClosedError(GaltonError):
    """A call on an SDK Client after its ``close()``: open a new Client."""


_BY_CODE: dict[ResultCode, type[RemoteError]] = {
    cls.code: cls
    for cls in (
        NotFoundError,
        IncorrectStateError,
        FeatureUnsupportedError,
        OperationFailedError,
        InvalidArgumentError,
        MalformedRequestError,
        UnknownOperationError,
        NameNotUniqueError,
        UnsupportedVersionError,
        PhysicsError,
        ResourceLimitError,
        ControlHeldError,
        RoleDeniedError,
    )
}


def error_for_code(code: int, message: str,
                   details: dict[str, Any] | None = None) -> RemoteError:
    """Build the exception that a failure code stands for (unknown codes: OperationFailed)."""
    try:
        cls = _BY_CODE[ResultCode(code)]
    except (ValueError, KeyError):
        return OperationFailedError(f"unknown result code {code}: {message}", details)
    return cls(message, details)


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """A ' (did you mean ...?)' suffix naming the closest choices, or ''."""
    close = difflib.get_close_matches(word, list(choices), n=3, cutoff=0.6)
    if not close:
        return ""
    return " (did you mean " + " or ".join(repr(c) for c in close) + "?)"


QUOTE_LIMIT = 100  # characters of an offending value an error message may quote
_QUOTER = reprlib.Repr()
_QUOTER.maxlevel, _QUOTER.maxdict, _QUOTER.maxlist, _QUOTER.maxtuple = 3, 4, 4, 4
_QUOTER.maxstring, _QUOTER.maxother, _QUOTER.maxlong = 60, 60, 40


def brief(value: Any, limit: int = QUOTE_LIMIT) -> str:
    """A repr of ``value`` of at most ``limit`` characters, cheap however big or deep the
    value is: an error message must never echo a 50 MB field back to its sender."""
    if isinstance(value, str | bytes | bytearray) and len(value) > limit:
        head = repr(value[:limit])
        text = f"{head[:limit]}... ({len(value)} {'chars' if isinstance(value, str) else 'bytes'})"
    else:
        text = _QUOTER.repr(value)
    return text if len(text) <= limit + 20 else text[:limit] + "..."


def unknown_names(kind: str, missing: Sequence[str], known: Iterable[str]) -> NotFoundError:
    """NotFound for names a request gave that are not ``known``: it names the first (with
    a "did you mean"), counts the rest, and lists up to 100 in its details."""
    first = missing[0]
    more = f" and {len(missing) - 1} more" if len(missing) > 1 else ""
    return NotFoundError(f"no {kind} named {brief(first)}{more}{did_you_mean(first, known)}",
                         {"missing": list(missing[:100]), "missing_count": len(missing)})
