"""Roles and what each may ask, shared by every front: Zenoh's ACL (zenoh_security.py) and
ZeroMQ's per-request check (zmq_auth.py) hold viewers to the same operations."""

from __future__ import annotations

from galton.daemon.access.users import OPERATOR, VIEWER
from galton.protocol.operations import OPERATIONS

# The read-only operations a viewer may ask, as each operation declares it
# (`Operation(viewer=True)`, protocol/operations.py): discovery (`galton-client daemons`)
# asks status and capabilities; `galton-client view` the others (a state stream changes no
# world).
VIEWER_OPERATIONS = tuple(name for name, op in OPERATIONS.items() if op.viewer)


def may_ask(role: str | None, op: str) -> bool:
    """Whether a client of that role may ask that operation (None: no users file, anyone)."""
    return role is None or role == OPERATOR or (role == VIEWER and op in VIEWER_OPERATIONS)
