"""Finding daemons through their liveliness tokens."""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import zenoh

from galton.client.transport.credentials import Credentials
from galton.client.transport.session import (
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

UNREACHABLE = "unreachable"


@dataclass
class DaemonInfo:
    """One daemon found on the network."""

    instance: str
    engine: str
    state: str
    sim_time: float
    entity_count: int
    error: str = ""
    host: dict[str, Any] = field(default_factory=dict)  # capabilities' host map
    zmq: list[str] = field(default_factory=list)  # its ZeroMQ control endpoints, if any

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @property
    def reachable(self) -> bool:
        return self.state != UNREACHABLE


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
    """Every visible daemon with its engine, state, host and ZeroMQ endpoints."""
    return [describe(session, name, timeout) for name in instances(session, timeout)]


def describe(session: zenoh.Session, name: str, timeout: float) -> DaemonInfo:
    """One daemon from its ``status`` and ``capabilities``; a daemon that answers status
    but not capabilities (busy past the timeout) is listed without host."""
    try:
        status = SimStatus.from_wire(_result(session, name, "status", timeout))
    except GaltonError as error:
        return DaemonInfo(name, "?", UNREACHABLE, 0.0, 0, str(error))
    info = DaemonInfo(name, status.engine, status.state, status.sim_time, status.entity_count)
    try:
        capabilities = _result(session, name, "capabilities", timeout)
    except GaltonError as error:
        info.error = f"capabilities: {error}"
        return info
    info.host = dict(capabilities.get("host") or {})
    info.zmq = [str(e) for e in (capabilities.get("zmq") or {}).get("control", [])]
    return info


def _result(session: zenoh.Session, name: str, op: str, timeout: float) -> dict[str, Any]:
    reply = query(session, Keys(name), op, None, timeout)
    reply.raise_for_code()
    return reply.result


def discover_at(connect: str | Sequence[str] | None, timeout: float = 2.0,
                credentials: Credentials | None = None) -> list[DaemonInfo]:
    """Open a session to ``connect`` (with these credentials), discover, close."""
    session = open_session(connect, credentials=credentials)
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
