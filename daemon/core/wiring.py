"""What the physics loop is given from outside, once: ``LoopWiring``, made by the composition
root (daemon/server.py) and frozen, so that nothing sets a loop's outlets after it is built.

A value known only once the fronts are open (the endpoints ``capabilities`` advertises,
whether a client is still there) is a function here, asked when needed, never a late
assignment.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass
from typing import Any, NamedTuple

from galton.daemon.core.calls import PolledSource, Publish
from galton.daemon.core.limits import DEFAULT_LIMITS, Limits


def _nowhere(topic: str, data: bytes) -> None:
    """An embedded loop with no fronts publishes nothing."""


def _nothing() -> dict[str, Any]:
    return {}


class Checkpoints(NamedTuple):
    """galton-daemon --state-dir: ``save`` the live world every ``period_s`` seconds."""

    save: Callable[[], None]
    period_s: float


@dataclass(frozen=True)
class LoopWiring:
    """The loop's outlets and settings: where it publishes, how it makes engines, its
    limits, the front it polls, and the hooks the daemon process adds."""

    instance: str
    # Telemetry, events and state streams' samples, msgpack already, to every front
    # (``Fronts.publish``), on the physics thread; each front decides what it carries.
    publish: Publish = _nowhere
    telemetry_rate_hz: float = 10.0
    engine_factory: Callable[[str], Any] | None = None  # load_model, predict, snapshots
    limits: Limits = DEFAULT_LIMITS
    polled: PolledSource | None = None  # a front read on the physics thread (ZeroMQ)
    snapshot_key: bytes | None = None  # galton-daemon --snapshot-key: blobs' seal
    # What ``capabilities`` adds from the fronts (ZeroMQ's endpoints), asked each time.
    advertised: Callable[[], dict[str, Any]] = _nothing
    # Whether a client is still there, as the fronts know it (Fronts.client_alive: Zenoh's
    # liveliness token, a ZeroMQ connection's last word): take_control and stream_states
    # tie what they give to it. None: nobody to ask (embedded, no session).
    client_alive: Callable[[str], bool | None] | None = None
    # Wraps each scene-changing request (spawn, delete, load_model...): galton-daemon makes
    # SIGTERM end the process at once inside it (server.sigterm_ends_at_once).
    work_guard: Callable[[], AbstractContextManager[None]] = nullcontext
    checkpoints: Checkpoints | None = None
