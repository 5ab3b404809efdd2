"""A fuzz campaign against a running daemon: seeded requests from the operations' own
declarations (``requests``), each checked for what the protocol promises.

- every request gets exactly one reply, in time, that decodes to a known result code;
- a rejected request leaves the world as it was: a hash of ``list``, the states, the
  parameters and the clock is the same before and after it (a step that diverged, answered
  PHYSICS_ERROR after its steps ran, is the one exception: its steps were work, not a
  rejection);
- the daemon is still serving at the end (the caller also checks its process).

With ``oversize``, requests whose replies would pass the daemon's reply limit follow
(``oversize.py``: each must be refused and change nothing); with ``unread``, a ZeroMQ client
pipelines that many requests and never reads them while others ask for ``status``
(``unread.py``: they must still be answered promptly).

``galton-client fuzz`` runs one; the test suite runs a short one on each engine.
"""

from __future__ import annotations

import hashlib
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import msgpack
import numpy as np

from galton.client.fuzz import oversize
from galton.client.fuzz.requests import RequestMaker
from galton.client.fuzz.snapshots import resealed_campaign
from galton.client.fuzz.unread import unread_flood, zmq_control
from galton.client.sdk.client import Client
from galton.protocol import (
    PROTOCOL_VERSION,
    GaltonError,
    PhysicsError,
    Reply,
    ResultCode,
    decode_reply,
)
from galton.protocol.operations import OPERATIONS

REPLY_TIMEOUT_S = 30.0
MAX_ENTITIES = 150  # the campaign resets the world past this, to keep requests quick


@dataclass
class FuzzReport:
    """What a campaign found; ``ok`` when it found nothing wrong."""

    seed: int
    requests: int = 0
    codes: Counter[str] = field(default_factory=Counter)
    missing_replies: list[str] = field(default_factory=list)
    untyped_replies: list[str] = field(default_factory=list)
    side_effects: list[str] = field(default_factory=list)
    # Re-sealed corrupt snapshots refused yet applied, or accepted inconsistent (``snapshots``)
    bad_restores: list[str] = field(default_factory=list)
    # Requests over the reply limit answered, or answered too big (``oversize``)
    oversize_cases: int = 0
    oversize_answered: list[str] = field(default_factory=list)
    # Requests a ZeroMQ client pipelined unread, and status requests it starved (``unread``)
    unread_sent: int = 0
    starved: list[str] = field(default_factory=list)
    skipped: list[str] = field(default_factory=list)  # cases this daemon could not be given
    seconds: float = 0.0

    @property
    def ok(self) -> bool:
        return not (self.missing_replies or self.untyped_replies or self.side_effects
                    or self.bad_restores or self.oversize_answered or self.starved)

    def to_dict(self) -> dict[str, Any]:
        return {"seed": self.seed, "requests": self.requests, "codes": dict(self.codes),
                "missing_replies": self.missing_replies[:20],
                "missing_count": len(self.missing_replies),
                "untyped_replies": self.untyped_replies[:20],
                "untyped_count": len(self.untyped_replies),
                "side_effects": self.side_effects[:20],
                "side_effect_count": len(self.side_effects),
                "bad_restores": self.bad_restores[:20], "oversize_cases": self.oversize_cases,
                "oversize_answered": self.oversize_answered[:20],
                "unread_sent": self.unread_sent, "starved": self.starved[:20],
                "skipped": self.skipped, "seconds": self.seconds, "ok": self.ok}


@dataclass
class WorldView:
    """What a rejected request must leave as it was, hashed; and what the maker needs."""

    digest: str
    names: list[str]
    state: str
    sim_time: float
    engine: str


def look(client: Client) -> WorldView:
    """Hash the world's list, states, parameters and clock (four requests)."""
    status = client.call("status")
    entities = sorted(client.call("list")["entities"], key=lambda e: e["name"])
    names = [e["name"] for e in entities]
    states: Any = "faulted"
    if not status["faulted"] and names:
        try:  # a playing world may diverge between the two requests
            result = client.call("get_states", {"names": names})
            states = [result["poses"], result["twists"]]
        except PhysicsError:
            pass
    clock = {k: status[k] for k in ("state", "step", "sim_time", "timestep", "target_rtf",
                                    "entity_count", "engine", "faulted")}
    blob = msgpack.packb([clock, entities, states, client.call("get_params")["params"]],
                         use_bin_type=True, default=str)
    return WorldView(hashlib.sha256(blob).hexdigest(), names, status["state"],
                     status["sim_time"], status["engine"])


def send(client: Client, key_op: str, payload: bytes, timeout: float) -> list[bytes]:
    """Every reply the daemon sent to one raw request."""
    return client.transport.send_raw(key_op, payload, timeout)


def run_campaign(client: Client, requests: int, seed: int = 0,
                 progress: Callable[[int], None] | None = None,
                 timeout: float = REPLY_TIMEOUT_S, resealed: int = 0,
                 oversize_cases: bool = False, unread: int = 0) -> FuzzReport:
    """Send ``requests`` fuzz requests one after the other and check each (see above);
    then restore ``resealed`` re-sealed corrupt snapshots of the world it left
    (``snapshots``); then the requests over the reply limit, and a flood of ``unread``
    requests from a ZeroMQ client that never reads (see above)."""
    report = FuzzReport(seed=seed)
    maker = RequestMaker(np.random.default_rng(seed))
    started = time.monotonic()
    view = _settle(client, look(client), maker)
    for index in range(requests):
        maker.names, maker.sim_time, maker.engine = view.names, view.sim_time, view.engine
        key_op, payload = maker.make()
        code = _check_reply(report, index, key_op, send(client, key_op, payload, timeout))
        after = look(client)
        still = view.state != "playing"  # a playing world's clock moves between two looks
        if code is not None and code != ResultCode.OK and still and \
                after.digest != view.digest and not _did_work(key_op, code):
            report.side_effects.append(f"#{index} {key_op} answered {code.name} but changed "
                                       f"the world: {payload[:200]!r}")
        view = _settle(client, after, maker)
        report.requests += 1
        if progress is not None:
            progress(index + 1)
    if resealed:
        client.call("pause")
        client.call("reset", {"scope": "state"})  # a faulted world takes no snapshot
        report.bad_restores = resealed_campaign(client, resealed, maker.rng,
                                                lambda: look(client).digest)
    if oversize_cases:
        _oversize(client, report, timeout)
    if unread:
        _unread(client, report, unread)
    client.call("status")  # still serving
    report.seconds = time.monotonic() - started
    return report


def _check_reply(report: FuzzReport, index: int | str, key_op: str,
                 replies: list[bytes]) -> ResultCode | None:
    if len(replies) != 1:
        report.missing_replies.append(f"#{index} {key_op}: {len(replies)} replies")
        return None
    try:
        code = decode_reply(replies[0]).code
    except GaltonError as error:
        report.untyped_replies.append(f"#{index} {key_op}: {error}")
        return None
    report.codes[code.name] += 1
    return code


def _did_work(op: str, code: ResultCode) -> bool:
    """A step request that diverged ran its steps: PHYSICS_ERROR is its outcome, not a
    rejection."""
    return code == ResultCode.PHYSICS_ERROR and op in OPERATIONS and OPERATIONS[op].steps


def _settle(client: Client, view: WorldView, maker: RequestMaker) -> WorldView:
    """Keep the world small and mostly still between requests: pause a playing world most
    of the time (while it plays, rejections are not checked: its clock moves between two
    looks), reset one grown past MAX_ENTITIES."""
    changed = False
    if view.state == "playing" and maker.chance(0.7):
        client.call("pause")
        changed = True
    if len(view.names) > MAX_ENTITIES:
        client.call("reset", {"scope": "all"})
        changed = True
    return look(client) if changed else view


def _oversize(client: Client, report: FuzzReport, timeout: float) -> None:
    """The requests over the reply limit (``oversize``), on a paused world; the limit is
    learnt from the first refusal that states it."""
    client.call("pause")
    client.call("reset", {"scope": "state"})  # a faulted world refuses any step first
    names = look(client).names
    limit: int | None = None
    for op, args in oversize.fixed_cases(names):
        reply = _oversize_case(client, report, op, args, limit, lambda: look(client).digest,
                               timeout)
        limit = limit or (None if reply is None else oversize.learn_limit(reply))
    if limit is None:
        report.skipped.append("oversize: the daemon stated no max_reply_bytes")
        return
    rays = oversize.rays_case(limit)
    if rays is None:
        report.skipped.append(f"oversize raycast: {limit} bytes of rays is too big to send")
    else:
        _oversize_case(client, report, *rays, limit, lambda: look(client).digest, timeout)
    _oversize_reads(client, report, limit, timeout)


def _oversize_reads(client: Client, report: FuzzReport, limit: int, timeout: float) -> None:
    """A step reading more bodies than a reply holds, in a world of that many (looked at
    in part: a whole ``list`` of it would pass the limit too); the world is reset after."""
    count = oversize.pile_size(limit)
    if count is None:
        report.skipped.append(f"oversize reads: {limit} bytes is over "
                              f"{oversize.MAX_PILE} bodies' reads")
        return
    names = oversize.pile_names(count)
    client.call("spawn", oversize.pile(count))

    def digest() -> str:
        status = client.call("status")
        states = client.call("get_states", {"names": names[:100]})
        clock = [status[k] for k in ("state", "step", "sim_time", "entity_count")]
        return hashlib.sha256(msgpack.packb([clock, states["poses"], states["twists"]],
                                            use_bin_type=True)).hexdigest()

    for op, args in oversize.reads_cases(names):
        _oversize_case(client, report, op, args, limit, digest, timeout)
    client.call("reset", {"scope": "all"})


def _oversize_case(client: Client, report: FuzzReport, op: str, args: dict[str, Any],
                   limit: int | None, digest: Callable[[], str], timeout: float
                   ) -> Reply | None:
    """Send one over-limit request and check it: one typed reply, a refusal no bigger than
    the limit, the world (as ``digest`` hashes it) unchanged."""
    index = f"oversize-{report.oversize_cases}"
    report.oversize_cases += 1
    report.requests += 1
    before = digest()
    payload = msgpack.packb({"v": PROTOCOL_VERSION, "op": op, "args": args}, use_bin_type=True)
    replies = send(client, op, payload, timeout)
    code = _check_reply(report, index, op, replies)
    if code is None:
        return None
    reply = decode_reply(replies[0])
    wrong = oversize.judge(op, reply, len(replies[0]), limit)
    if wrong is not None:
        report.oversize_answered.append(f"#{index} {wrong}")
    if code != ResultCode.OK and digest() != before:
        report.side_effects.append(f"#{index} {op} answered {code.name} but changed the world")
    return reply


def _unread(client: Client, report: FuzzReport, requests: int) -> None:
    endpoint = zmq_control(client)
    if endpoint is None:
        report.skipped.append("unread replies: the daemon serves no ZeroMQ front")
        return
    flood = unread_flood(endpoint, client, requests)
    report.unread_sent = flood.sent
    report.starved = flood.findings
