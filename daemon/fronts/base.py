"""What every front is: calls in; telemetry, events and state streams out. The composition
root (daemon/server.py) builds each front from its options (with what it rides on, as
ROS 2 the Zenoh session) and then opens, publishes to and closes them all through
``Fronts``, never one by name.

A front turns a transport's requests into ``Call`` objects and hands them to the core's
call interface (``CallPort``: daemon/core/calls.py), the only part of the core it may
import; the reply comes back through ``Call.respond``. Everything the core publishes
(telemetry, events, state streams) goes once to the list of fronts, each of which puts it
on its own wire or ignores it. A new front is one module (or package) here with this shape:
a class that subclasses ``Front`` (its defaults: nothing advertised, no clients of its own,
nothing to withdraw, no words on the ready line, not polled) and writes what it serves.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

from galton.daemon.core.calls import EVENTS, TELEMETRY, CallPort, PolledSource

__all__ = ["EVENTS", "TELEMETRY", "Front", "Fronts"]


class Front(Protocol):
    """One transport the daemon serves on. ``open``, ``publish`` and ``close`` are each
    front's own; the rest have defaults here for a front that subclasses this."""

    def open(self, core: CallPort) -> None:
        """Start taking calls: from now on requests go to ``core.dispatch``."""

    def publish(self, topic: str, data: bytes) -> None:
        """Put one sample on ``galton/<instance>/<topic>`` (``telemetry``, ``events`` or a
        state stream's topic), msgpack already; never block the physics thread on it."""

    def advertised(self) -> dict[str, Any]:
        """What ``capabilities`` tells clients about this front (empty: nothing)."""
        return {}

    def client_alive(self, client: str) -> bool | None:
        """Whether a client (an owner of state streams, a lease holder) is still there, as
        this front knows it: True (alive), False (gone: its token went, or its connection
        closed or fell silent), None (not a client of this front, or it cannot tell)."""
        return None

    def withdraw(self) -> None:
        """Stop being found (the first step of a shutdown); pending calls still get answers."""
        return None

    def ready_words(self) -> str:
        """What the daemon's ready line says of this front (``zmq=tcp://...``), words
        separated by spaces; empty: nothing. Users and tests parse that line."""
        return ""

    def polled(self) -> PolledSource | None:
        """The source the physics thread polls itself for this front's calls (ZeroMQ), or
        None: the front hands calls in from its own threads (``core.dispatch``)."""
        return None

    def close(self) -> None:
        """Release the front's sockets, after the physics thread has stopped."""


class Fronts:
    """The fronts of one daemon, published to as one: no hand copy per transport."""

    def __init__(self, fronts: Sequence[Front] = ()) -> None:
        self.fronts: list[Front] = list(fronts)

    def open(self, core: CallPort) -> None:
        """Open in order: a front built on another's session opens after it."""
        for front in self.fronts:
            front.open(core)

    def publish(self, topic: str, data: bytes) -> None:
        for front in self.fronts:
            front.publish(topic, data)

    def advertised(self) -> dict[str, Any]:
        found: dict[str, Any] = {}
        for front in self.fronts:
            found.update(front.advertised())
        return found

    def client_alive(self, client: str) -> bool | None:
        """The first front's answer that knows the client (a client is one front's: a
        Zenoh client id, a ZeroMQ connection's name), else None."""
        for front in self.fronts:
            alive = front.client_alive(client)
            if alive is not None:
                return alive
        return None

    def ready_words(self) -> str:
        """The fronts' words on the ready line, in order, one space apart."""
        return " ".join(words for front in self.fronts if (words := front.ready_words()))

    def polled(self) -> PolledSource | None:
        """The one front the physics thread polls (the wiring's ``polled``), if any."""
        found = [source for front in self.fronts if (source := front.polled()) is not None]
        if len(found) > 1:
            raise ValueError("at most one front can be polled by the physics thread")
        return found[0] if found else None

    def withdraw(self) -> None:
        for front in self.fronts:
            front.withdraw()

    def close(self) -> None:
        """Close in reverse order: a front built on another's session closes before it."""
        for front in reversed(self.fronts):
            front.close()
