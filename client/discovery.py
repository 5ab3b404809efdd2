"""Finding daemons through their liveliness tokens."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import zenoh

from galton.client.session import (
    checked_timeout,
    close_session,
    open_session,
    query,
    undeclare,
)
from galton.protocol import (
    DaemonUnreachableError,
    GaltonError,
    Keys,
    RequestTimeoutError,
    SimStatus,
    instance_from_liveliness_key,
)
from galton.protocol.keys import LIVELINESS_PATTERN


@dataclass
class DaemonInfo:
    """One daemon found on the network."""

    instance: str
    engine: str
    state: str
    sim_time: float
    entity_count: int
    error: str = ""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def instances(session: zenoh.Session, timeout: float = 2.0) -> list[str]:
    """Names of every daemon instance whose liveliness token is visible."""
    found = set()
    for reply in session.liveliness().get(LIVELINESS_PATTERN,
                                          timeout=checked_timeout(timeout)):
        if reply.ok is not None:
            name = instance_from_liveliness_key(str(reply.ok.key_expr))
            if name:
                found.add(name)
    return sorted(found)


def discover(session: zenoh.Session, timeout: float = 2.0) -> list[DaemonInfo]:
    """Every visible daemon with its engine and state."""
    daemons = []
    for name in instances(session, timeout):
        try:
            reply = query(session, Keys(name), "status", None, timeout)
            reply.raise_for_code()
            status = SimStatus.from_wire(reply.result)
            daemons.append(DaemonInfo(name, status.engine, status.state, status.sim_time,
                                      status.entity_count))
        except GaltonError as error:
            daemons.append(DaemonInfo(name, "?", "unreachable", 0.0, 0, str(error)))
    return daemons


def discover_at(connect: str | Sequence[str] | None, timeout: float = 2.0) -> list[DaemonInfo]:
    """Open a session to ``connect``, discover, close."""
    session = open_session(connect)
    try:
        return discover(session, timeout)
    finally:
        close_session(session)


def wait_for_daemon(session: zenoh.Session, instance: str, timeout: float,
                    alive: threading.Event | None = None) -> None:
    """Block until the instance's liveliness token appears, or raise after ``timeout``."""
    wait = checked_timeout(timeout)
    appeared = alive or threading.Event()

    def on_token(sample: zenoh.Sample) -> None:
        if sample.kind == zenoh.SampleKind.PUT:
            appeared.set()

    subscriber = session.liveliness().declare_subscriber(
        Keys(instance).alive, on_token, history=True)
    try:
        if not appeared.wait(wait):
            raise RequestTimeoutError(f"daemon {instance!r} did not appear within {timeout:g} s")
    finally:
        undeclare(subscriber)


__all__ = ["DaemonInfo", "DaemonUnreachableError", "discover", "discover_at", "instances",
           "wait_for_daemon"]
