"""Every reply is bounded by ``max_reply_bytes`` (issue 35): a request whose reply would pass
it is refused with RESOURCE_LIMIT, never answered with a reply a client cannot hold.

Where the size follows from the request (a raw render's pixels, a ray count, a snapshot's
blob before its slot is kept, the states a `step`, `run_until`, `predict` or
`set_joint_states` reads back) the request is refused before any work, so a request that
changes the world is never refused after changing it; any other reply (a `contacts` of a
huge pile, a png render) is measured once encoded and replaced by the refusal, so the
daemon never sends one that is too big. Such replies are of reads, which change nothing.
"""

from __future__ import annotations

from collections.abc import Sequence

from galton.daemon.core.limits import MIB
from galton.protocol import POSE_WIDTH, TWIST_WIDTH, ResourceLimitError

# Bytes a raw render's pixel takes per output, and a raycast's ray at least (hit flag,
# point, normal, distance; the entity's name comes on top).
RAW_PIXEL_BYTES = {"rgb": 3, "depth": 4, "segmentation": 4}
RAY_BYTES = 1 + 8 * 7
# A reply's envelope and its result map's keys and small values (version, code, step, sim
# time, counts, flags): well over what they take, so an estimate is never under the reply.
ENVELOPE_BYTES = 512
NAME_HEADER_BYTES = 5  # msgpack's header of one string (3 for a name of up to 512 bytes)
VALUE_BYTES = 8  # one float64 of a packed array


def too_big(what: str, size: int, limit: int, instead: str) -> ResourceLimitError:
    return ResourceLimitError(
        f"{what} would be {size} bytes (about {size / MIB:.1f} MiB); replies are at most "
        f"max_reply_bytes = {limit} ({instead}, or galton-daemon --limit max_reply_bytes=N)",
        {"limit": "max_reply_bytes", "max": limit, "size": size})


def require_room(what: str, size: int, limit: int, instead: str) -> None:
    """Refuse up front a request whose reply is known to pass the limit."""
    if size > limit:
        raise too_big(what, size, limit, instead)


def reads_size(bodies: Sequence[str] | None, joints: Sequence[str] | None, samples: int = 1,
               joint_values: int = 3) -> int:
    """At least the encoded size of a reply reading ``bodies`` (a pose and a twist each)
    and ``joints`` (``joint_values`` numbers each) ``samples`` times, with each name once:
    what a step request's reads will take, known before its first step."""
    bodies, joints = bodies or (), joints or ()
    # One join and one encode: on the request path of every step that reads (a name at a
    # time took 108 us for 1,000 names).
    count = len(bodies) + len(joints)
    names = len("".join((*bodies, *joints)).encode()) + count * NAME_HEADER_BYTES
    per_sample = len(bodies) * (POSE_WIDTH + TWIST_WIDTH) + len(joints) * joint_values
    return ENVELOPE_BYTES + names + samples * VALUE_BYTES * per_sample
