"""What one request may ask of a daemon, and when a world counts as diverged.

Every limit is checked before any work is done, so a request over one is refused with
RESOURCE_LIMIT (or INVALID_ARGUMENT for a value out of its range) and changes nothing.
``galton-daemon`` takes each as an option; docs/protocol.md ("Limits") lists them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field, fields
from typing import Any

from galton.protocol import DecodeLimits
from galton.protocol.operations import OPERATIONS

MIB = 1024 * 1024


@dataclass(frozen=True)
class Limits:
    """A daemon's limits; the defaults suit a robot's on-board computer."""

    max_request_bytes: int = 16 * MIB  # one request's payload, before it is decoded
    max_depth: int = 16  # maps and lists nested in one request
    max_string_bytes: int = 4096  # any one string of a request (names are ≤ 128 chars)
    max_model_bytes: int = 16 * MIB  # a model's text, or the file a load_model path names
    max_entities: int = 100_000  # entities in one world
    max_worlds: int = 8  # worlds one daemon holds, the live one included
    max_snapshots: int = 16  # named snapshot slots one daemon holds
    max_snapshot_bytes: int = 256 * MIB  # all slots together
    # Pixels one render request asks for, all cameras together: a full-HD frame (the lead's
    # benchmarks/render_rtf.py holds a playing 100-ball world at RTF >= 0.95 under it).
    max_pixels: int = 1920 * 1080
    # Seconds a render may hold the physics thread, expected from its pixels at the rate its
    # engine's renders were measured at: one telemetry period at the default 10 Hz.
    max_render_seconds: float = 0.1
    max_rays: int = 1_000_000  # rays one raycast request casts
    max_steps: int = 1_000_000_000  # steps one step / run_until request may take
    max_reply_bytes: int = 64 * MIB  # any one reply (daemon/core/reply_limit.py)
    # Seconds a ZeroMQ connection holding state streams may send nothing before they end
    # (it may have stopped without closing; the SDK sends a status a third of this apart).
    zmq_silence_s: float = 10.0
    max_position: float = 1e6  # metres from the origin beyond which a world has diverged
    max_speed: float = 1e5  # m/s (or rad/s) beyond which a world has diverged
    # Native threads a prediction's futures step on (engines that release the GIL): the
    # cores this process may use.
    future_threads: int = field(default_factory=lambda: len(os.sched_getaffinity(0)))

    def __post_init__(self) -> None:
        for spec in fields(self):
            value = getattr(self, spec.name)
            if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
                raise ValueError(f"limit {spec.name} must be a positive number, got {value!r}")

    def to_wire(self) -> dict[str, Any]:
        return {spec.name: getattr(self, spec.name) for spec in fields(self)}


DEFAULT_LIMITS = Limits()


def parse_limits(items: list[str]) -> Limits:
    """``NAME=VALUE`` pairs (``galton-daemon --limit``) over the defaults; ValueError says
    what is wrong."""
    known = {spec.name: spec for spec in fields(Limits)}
    values: dict[str, Any] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip().replace("-", "_")
        if not sep or name not in known:
            raise ValueError(f"--limit {item!r}: use NAME=VALUE with NAME one of "
                             f"{', '.join(known)}")
        kind = int if isinstance(getattr(DEFAULT_LIMITS, name), int) else float
        try:
            values[name] = kind(float(text)) if kind is int else kind(text)
        except ValueError as exc:
            raise ValueError(f"--limit {item!r}: {text!r} is not a number") from exc
    return Limits(**values)


def describe_limits() -> str:
    return ", ".join(f"{spec.name}={getattr(DEFAULT_LIMITS, spec.name)}"
                     for spec in fields(Limits))


def decode_limits(limits: Limits) -> DecodeLimits:
    """What decoding a request holds it to: its size, nesting and string lengths (a field
    declared long text, such as a model's, is exempt from max_string_bytes)."""
    return DecodeLimits(
        max_bytes=limits.max_request_bytes, max_depth=limits.max_depth,
        max_string=limits.max_string_bytes,
        long_text_keys=frozenset(arg.name for op in OPERATIONS.values() for arg in op.args
                                 if arg.long_text))
