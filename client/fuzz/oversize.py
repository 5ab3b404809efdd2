"""Requests whose replies would pass the daemon's reply limit (issue 35, item 6): absurd
prediction horizons, a raw render of the most pixels a request may ask, as many rays as
the limit allows and one more, a step reading more bodies than a reply may carry.

Each must be refused (RESOURCE_LIMIT, or INVALID_ARGUMENT where another limit such as
``max_steps`` comes first), change nothing, and never be answered with a reply over the
limit. The limit is ``max_reply_bytes``, which a daemon states in the details of its first
such refusal (``learn_limit``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.protocol import Reply, ResultCode, pack_f64

REFUSALS = (ResultCode.RESOURCE_LIMIT, ResultCode.INVALID_ARGUMENT)
ABSURD_HORIZON_S = 1e6  # sampled every step: gigabytes of times alone
MAX_SIDE = 4096  # a camera of 4096 x 4096 (past the default max_pixels), every output raw
BODY_BYTES = 8 * 13  # a body's pose and twist in a step's reply, its name on top
RAY_BYTES = 1 + 8 * 7  # a ray's hit flag, point, normal and distance at least
MAX_PILE = 5_000  # bodies the campaign spawns to make a step's reads pass the limit
MAX_RAY_REQUEST_BYTES = 4 * 1024 * 1024  # rays sent (two points a ray) to pass the limit


def learn_limit(reply: Reply) -> int | None:
    """``max_reply_bytes`` as a RESOURCE_LIMIT refusal of it states it, else None."""
    details = reply.details
    if reply.code == ResultCode.RESOURCE_LIMIT and details.get("limit") == "max_reply_bytes":
        limit = details.get("max")
        return limit if isinstance(limit, int) else None
    return None


def fixed_cases(names: list[str]) -> list[tuple[str, dict[str, Any]]]:
    """The cases over any limit a daemon would run with: a prediction sampling every step
    for 10⁶ s (alone, and reading bodies), and a raw render of 4096 x 4096 pixels with
    every output (about 184 MB)."""
    camera = {"eye": [3.0, 0.0, 2.0], "target": [0.0, 0.0, 0.0], "width": MAX_SIDE,
              "height": MAX_SIDE, "outputs": ["rgb", "depth", "segmentation"]}
    cases: list[tuple[str, dict[str, Any]]] = [
        ("predict", {"horizon": ABSURD_HORIZON_S}),
        ("render", {"cameras": [camera], "format": "raw"})]
    if names:
        cases.insert(1, ("predict", {"horizon": ABSURD_HORIZON_S, "read": names[:100]}))
    return cases


def pile_size(limit: int) -> int | None:
    """Bodies whose reads in one step reply pass ``limit``; None past MAX_PILE (a daemon
    with the default limit would need some 650,000)."""
    count = limit // BODY_BYTES + 1
    return count if count <= MAX_PILE else None


def pile(count: int) -> dict[str, Any]:
    """A spawn of ``count`` small static spheres in a row, named ``oversize{i}``."""
    poses = np.zeros((count, 7))
    poses[:, 0] = np.arange(count) * 0.05
    poses[:, 2], poses[:, 6] = 0.5, 1.0
    return {"groups": [{"shape": "sphere", "size": [0.01], "static": True,
                        "names": pile_names(count), "poses": pack_f64(poses)}]}


def pile_names(count: int) -> list[str]:
    return [f"oversize{i}" for i in range(count)]


def reads_cases(names: list[str]) -> list[tuple[str, dict[str, Any]]]:
    """Requests that step, or set, then read ``names``: a reply over the limit."""
    return [("step", {"count": 1, "read": names}),
            ("run_until", {"sim_time": 1e3, "read": names,
                           "until_rest": {"speed": 1e-3, "every": 0.01}})]


def rays_case(limit: int) -> tuple[str, dict[str, Any]] | None:
    """A raycast of one ray more than the limit's reply holds, when that request is small
    enough to send (4 MiB)."""
    count = limit // RAY_BYTES + 1
    if count * 48 > MAX_RAY_REQUEST_BYTES:
        return None
    origins = np.tile([0.0, 0.0, 2.0], (count, 1))
    return ("raycast", {"origins": pack_f64(origins),
                        "directions": pack_f64(np.tile([0.0, 0.0, -1.0], (count, 1)))})


def judge(op: str, reply: Reply, size: int, limit: int | None) -> str | None:
    """What is wrong with the reply to an over-limit request, if anything."""
    if limit is not None and size > limit:
        return f"{op}: a reply of {size} bytes, over max_reply_bytes = {limit}"
    if reply.code not in REFUSALS:
        return f"{op}: answered {reply.code.name}, not refused ({reply.message[:200]})"
    return None
