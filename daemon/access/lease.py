"""The control lease (issue 28): one client at a time may hold control of a daemon.

While a client holds it, every request that changes a world or steps one (the registry's
``mutates`` and ``steps``, protocol/operations.py) from anyone else is refused with
CONTROL_HELD before anything is applied; reads stay open to all. ``take_control`` and
``release_control`` change who may mutate, not the scene: they are not ``mutates``.

Who sent a request: its envelope's ``client`` (the SDK's id, whose Zenoh liveliness token
``galton/_clients/<id>`` the daemon watches), else its ZeroMQ connection (``Call.peer``). A
request with neither is anonymous and is refused while anyone holds control. A request is
the holder's when it carries the holder's id or comes on the connection control was taken
on (an SDK client over ZeroMQ opens one connection per calling thread, all with its id).

The lease ends when its holder releases it or disappears: its token goes, or the ZeroMQ
connection it was taken on closes (``client_gone``, called on the physics thread; the
holder's long step ends with it in daemon/core/time_control.py). Every change is announced by a
``control`` event: ``{holder, change}`` with change ``taken``, ``released`` or ``lost``.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from galton.daemon.core.calls import Call
from galton.daemon.core.context import AccessContext
from galton.protocol import ControlHeldError, InvalidArgumentError
from galton.protocol import requests as rq
from galton.protocol.operations import Operation

NO_IDENTITY = (
    "take_control needs to know who asks: send the envelope's 'client' (the id of your "
    "liveliness token galton/_clients/<id>, which the SDK sends with every request), or "
    "ask over ZeroMQ, where the connection names you")
# A client id that names one liveliness token: one key chunk, no wildcard ('*', '$') and
# nothing Zenoh refuses in a key ('?', '#'). "*" would find any client's token alive, and
# no token's going would ever name it: control held for ever.
TOKEN_ID = re.compile(r"[^/*$?#]+")


@dataclass(frozen=True)
class Holder:
    """Who holds control: the id it gave and the connection it took control on."""

    client: str | None
    peer: str | None

    @property
    def name(self) -> str:
        """The id status and events show: the client's id, else its connection."""
        return self.client or self.peer or ""

    def sent(self, call: Call) -> bool:
        """Whether this request is the holder's (by its id, or on its connection)."""
        return ((self.client is not None and call.client == self.client)
                or (self.peer is not None and call.peer == self.peer))

    def gone_with(self, who: str) -> bool:
        """Whether the vanished client id or closed connection ``who`` was the holder: the
        connection control was taken on over ZeroMQ (a Zenoh token named like its id, which
        anyone may declare, is not it), else the client's token."""
        return who == (self.peer if self.peer is not None else self.client)


class Lease:
    """The daemon's one lease. Changed only on the physics thread; ``controller`` may be
    read from any thread (``holder`` is swapped whole)."""

    def __init__(self) -> None:
        self.holder: Holder | None = None

    @property
    def controller(self) -> str | None:
        """The holder's id (status's ``controller``), or None when nobody holds control."""
        holder = self.holder
        return None if holder is None else holder.name


def check(ctx: AccessContext, call: Call, op: Operation) -> None:
    """Refuse a request that would change or step a world while another client holds
    control (called before its handler runs, so a refused request changed nothing)."""
    holder = ctx.lease.holder
    if holder is None or not (op.mutates or op.steps) or holder.sent(call):
        return
    raise _held(holder, f"{op.name} from {_asker(call)} would change the world and is refused")


def take_control(ctx: AccessContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    """Take the lease, or keep it (taking it again is no change); refused while another
    client holds it."""
    if call.client is None and call.peer is None:
        raise InvalidArgumentError(NO_IDENTITY)
    if call.peer is None and call.client is not None \
            and not TOKEN_ID.fullmatch(call.client):
        raise InvalidArgumentError(
            f"client {call.client!r} names no single liveliness token galton/_clients/<id>: "
            "control is tied to that token, so the id may hold no '/', '*', '$', '?' or '#'")
    if call.peer is None and ctx.client_alive is not None and call.client is not None \
            and not ctx.client_alive(call.client):
        # A made-up id would hold control for ever: nothing would ever say it has gone.
        raise InvalidArgumentError(
            f"client {call.client!r} holds no liveliness token galton/_clients/"
            f"{call.client}: control is tied to that token (the SDK declares it)")
    holder = ctx.lease.holder
    if holder is not None:
        if holder.sent(call):
            return {"controller": holder.name, "taken": False}
        raise _held(holder, "take_control is refused")
    taker = Holder(call.client, call.peer)
    ctx.lease.holder = taker
    _announce(ctx, taker, "taken")
    return {"controller": taker.name, "taken": True}


def release_control(ctx: AccessContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    """Give the lease back (its holder only); with nobody holding it, nothing to do."""
    holder = ctx.lease.holder
    if holder is None:
        return {"controller": None, "released": False}
    if not holder.sent(call):
        raise _held(holder, "release_control is refused: only the holder releases control")
    ctx.lease.holder = None
    _announce(ctx, holder, "released")
    return {"controller": None, "released": True}


def client_gone(ctx: AccessContext, who: str) -> None:
    """A client's token went, or a ZeroMQ connection closed: if it held control, the lease
    ends now."""
    holder = ctx.lease.holder
    if holder is not None and holder.gone_with(who):
        ctx.lease.holder = None
        _announce(ctx, holder, "lost")


def _held(holder: Holder, what: str) -> ControlHeldError:
    return ControlHeldError(
        f"{what}: client {holder.name!r} holds control of this daemon until it releases it "
        "or disappears (reads stay open to all)",
        {"controller": holder.name})


def _asker(call: Call) -> str:
    if call.client is not None:
        return f"client {call.client!r}"
    if call.peer is not None:
        return f"connection {call.peer}"
    return "an anonymous request (no 'client' in its envelope)"


def _announce(ctx: AccessContext, holder: Holder, change: str) -> None:
    ctx.emit({"kind": "control", "holder": holder.name, "change": change})
