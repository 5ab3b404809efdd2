"""A ZeroMQ client that never reads its replies (issue 35, item 8): it pipelines requests
until the daemon pushes back (its sends would block), while a second ZeroMQ client and the
campaign's own client ask for ``status``. Both must be answered promptly, during the flood
and once the flooding client has gone (the front once stayed silent 22 s after it closed).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

import msgpack
import zmq

from galton.client.sdk.client import Client
from galton.protocol import PROTOCOL_VERSION

PROMPT_S = 5.0  # a status behind a flood took 9-15 s before issue 35, milliseconds after
CHECKS = 3  # status round trips during the flood
FLOOD_CAMERA = {"eye": [2.0, 0.0, 1.0], "target": [0.0, 0.0, 0.5], "width": 64,
                "height": 48}


@dataclass
class FloodResult:
    """How many requests the flood pipelined, and what went wrong."""

    sent: int = 0
    findings: list[str] = field(default_factory=list)


def zmq_control(client: Client) -> str | None:
    """The daemon's ZeroMQ control endpoint, as ``capabilities`` names it (None: no
    ZeroMQ front)."""
    advertised = client.call("capabilities").get("zmq") or {}
    control = advertised.get("control") or []
    return str(control[0]) if control else None


def envelope(op: str, args: dict[str, object] | None = None) -> bytes:
    payload: bytes = msgpack.packb({"v": PROTOCOL_VERSION, "op": op, "args": args or {}},
                                   use_bin_type=True)
    return payload


def unread_flood(endpoint: str, client: Client, requests: int) -> FloodResult:
    """Pipeline up to ``requests`` small renders and reads on one DEALER that never reads,
    then time ``status`` from another DEALER and from ``client``, during the flood and
    after the flooding socket closed."""
    result = FloodResult()
    context: zmq.Context[zmq.Socket[bytes]] = zmq.Context()
    try:
        flood, polite = context.socket(zmq.DEALER), context.socket(zmq.DEALER)
        for socket in (flood, polite):
            socket.connect(endpoint)
        result.sent = _pipeline(flood, requests)
        for _ in range(CHECKS):
            _check(result, "ZeroMQ status during the flood", lambda: _round_trip(polite))
            _check(result, "the campaign's status during the flood",
                   lambda: client.call("status", timeout=4 * PROMPT_S))
        flood.close(linger=0)
        _check(result, "ZeroMQ status after the flood closed", lambda: _round_trip(polite))
    finally:
        context.destroy(linger=0)
    return result


def _pipeline(flood: zmq.Socket[bytes], requests: int) -> int:
    """Send without reading until ``requests`` are out or the daemon pushes back."""
    ops = [envelope("render", {"cameras": [FLOOD_CAMERA]}), envelope("get_states"),
           envelope("status")]
    for index in range(requests):
        try:
            flood.send(ops[index % len(ops)], zmq.NOBLOCK)
        except zmq.Again:  # its queue is full: back-pressure on this client alone
            return index
    return requests


def _round_trip(socket: zmq.Socket[bytes]) -> None:
    socket.send(envelope("status"))
    if not socket.poll(int(4 * PROMPT_S * 1000)):
        raise TimeoutError("no reply")
    reply = msgpack.unpackb(socket.recv_multipart()[-1], raw=False)
    if reply.get("code") != 0:
        raise RuntimeError(f"answered {reply.get('code_name')}")


def _check(result: FloodResult, what: str, ask: Callable[[], object]) -> None:
    started = time.monotonic()
    try:
        ask()
    except Exception as error:  # any failure is the finding
        result.findings.append(f"{what}: {type(error).__name__}: {error}"[:300])
        return
    took = time.monotonic() - started
    if took > PROMPT_S:
        result.findings.append(f"{what} took {took:.1f} s (at most {PROMPT_S} s)")
