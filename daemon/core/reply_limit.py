"""Every reply is bounded by ``max_reply_bytes`` (issue 35): a request whose reply would pass
it is refused with RESOURCE_LIMIT, never answered with a reply a client cannot hold.

Where the size follows from the request (a raw render's pixels, a ray count, a snapshot's
blob before its slot is kept) the request is refused before any work; any other reply (a
`contacts` of a huge pile, a png render) is measured once encoded and replaced by the
refusal, so the daemon never sends one that is too big. Such replies are of reads, which
change nothing.
"""

from __future__ import annotations

from galton.daemon.core.limits import MIB
from galton.protocol import ResourceLimitError

# Bytes a raw render's pixel takes per output, and a raycast's ray at least (hit flag,
# point, normal, distance; the entity's name comes on top).
RAW_PIXEL_BYTES = {"rgb": 3, "depth": 4, "segmentation": 4}
RAY_BYTES = 1 + 8 * 7


def too_big(what: str, size: int, limit: int, instead: str) -> ResourceLimitError:
    return ResourceLimitError(
        f"{what} would be {size} bytes (about {size / MIB:.1f} MiB); replies are at most "
        f"max_reply_bytes = {limit} ({instead}, or galton-daemon --limit max_reply_bytes=N)",
        {"limit": "max_reply_bytes", "max": limit, "size": size})


def require_room(what: str, size: int, limit: int, instead: str) -> None:
    """Refuse up front a request whose reply is known to pass the limit."""
    if size > limit:
        raise too_big(what, size, limit, instead)
