"""Roles and what each may ask, shared by every front: Zenoh's ACL (zenoh_security.py) and
ZeroMQ's per-request check (zmq_auth.py) hold viewers to the same operations."""

from __future__ import annotations

from galton.daemon.access.users import OPERATOR, VIEWER

# Read-only operations a viewer may ask: discovery (`galton-client daemons`) asks the
# first two; `galton-client view` the others (a state stream changes no world).
VIEWER_OPERATIONS = ("status", "capabilities", "list", "list_worlds", "contacts",
                     "stream_states", "close_stream", "get_shapes")


def may_ask(role: str | None, op: str) -> bool:
    """Whether a client of that role may ask that operation (None: no users file, anyone)."""
    return role is None or role == OPERATOR or (role == VIEWER and op in VIEWER_OPERATIONS)
