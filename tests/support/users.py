"""A users file with an operator (alice, TLS name alice.robot) and a viewer (bob, by hash),
shared by the daemon's access tests and the viewer's role tests."""

from __future__ import annotations

from pathlib import Path

from galton.client import Credentials
from galton.protocol.auth import wire_password

USERS = """
[users.alice]
role = "operator"
password = "alice-secret-1"
tls_name = "alice.robot"

[users.bob]
role = "viewer"
password_sha256 = "{bob_hash}"
tls_name = "bob.view"
"""
ALICE = Credentials("alice", "alice-secret-1")
BOB = Credentials("bob", "bob-secret-2")


def users_file(folder: Path) -> Path:
    path = folder / "users.toml"
    path.write_text(USERS.format(bob_hash=wire_password("bob", "bob-secret-2")))
    path.chmod(0o600)
    return path
