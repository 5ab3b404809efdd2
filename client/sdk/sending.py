"""What the SDK sends: each method builds its operation's declared request (a msgspec Struct
of ``galton.protocol.requests``) and ``Client._send`` turns it into the wire's ``args`` map
here, held to its declaration before it leaves.

A Struct checks nothing when it is built (msgspec validates types and ``Meta`` ranges only
when decoding), so the map is decoded here by the daemon's own ``decode_args``: a value of
the wrong type, out of its declared range or not one of its choices raises the
INVALID_ARGUMENT the daemon would answer, word for word, and nothing is sent. It costs a
few microseconds a request, against a round trip; one declaration, one check, two places.
What needs the world or the daemon's options (names, limits, finite rows) stays the
daemon's to judge.
"""

from __future__ import annotations

from typing import Any

import msgpack

from galton.protocol import requests as rq
from galton.protocol.errors import InvalidArgumentError
from galton.protocol.operations import operation


def wire_args(op: str, request: rq.Args) -> dict[str, Any]:
    """``request`` as ``op``'s args map, or InvalidArgumentError as the daemon would refuse
    it; a request of another type than ``op`` declares is an SDK bug (TypeError)."""
    declared = operation(op).request
    if type(request) is not declared:
        raise TypeError(f"{op} takes a {declared.__name__} request, "
                        f"not {type(request).__name__}")
    args = rq.encode_args(request)
    try:
        rq.decode_args(op, declared, args)
    except InvalidArgumentError as refused:
        _check_as_received(op, declared, args, refused)
    return args


def _check_as_received(op: str, declared: type[rq.Args], args: dict[str, Any],
                       refused: InvalidArgumentError) -> None:
    """msgspec takes no numpy scalar for a number, where msgpack sends a ``np.float64`` as
    the float it is: a map refused as built is decoded again as the daemon receives it,
    and refused only if the daemon would refuse it (in its words). One msgpack cannot send
    (an ``np.int64``) keeps the first refusal, which names the value's type."""
    try:
        received = msgpack.unpackb(msgpack.packb(args, use_bin_type=True), raw=False,
                                   strict_map_key=True)
    except (TypeError, ValueError):
        raise refused from None
    rq.decode_args(op, declared, received)
