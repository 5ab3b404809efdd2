"""User names and the password that goes on the wire, shared by the daemon and clients.

Zenoh's user/password check (``transport/auth/usrpwd``) is a challenge and response: the
password never crosses the network, but the daemon must hold it, one ``user:password``
line per user in a dictionary file. So that a users file need not hold clear passwords,
the password Zenoh sees is ``sha256("galton:" + user + ":" + password)`` in hex, which
the SDK computes from the clear password. That hash is **password-equivalent** for Zenoh:
whoever reads it can log in as that user (docs/SECURITY.md).
"""

from __future__ import annotations

import hashlib
import re

from galton.protocol.errors import InvalidArgumentError, brief

WIRE_SALT = "galton"
HEX_DIGEST_LENGTH = 64  # sha256 in hex
# One Zenoh dictionary line is ``user:password``, split at the first ':'.
# fullmatch, not match: ``$`` would let a trailing line break through (a broken line).
_USER_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.@-]{0,63}$")
_HEX_RE = re.compile(r"^[0-9a-fA-F]{64}$")


def validate_user_name(name: object) -> str:
    """A user name: 1-64 letters, digits, '_', '.', '@' or '-' (not first), no ':'."""
    if not isinstance(name, str) or not _USER_RE.fullmatch(name):
        raise InvalidArgumentError(
            f"user name {brief(name)} is not valid: use 1-64 letters, digits, '_', '.', '@' "
            "or '-', not starting with '.', '@' or '-'")
    return name


def wire_password(user: str, password: str) -> str:
    """What Zenoh's usrpwd compares for ``user``: the salted sha256 of the clear password."""
    if not password:
        raise InvalidArgumentError(f"the password of user {user!r} is empty")
    text = f"{WIRE_SALT}:{validate_user_name(user)}:{password}"
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def is_wire_hash(text: object) -> bool:
    """Whether ``text`` has the form of a wire password: 64 hex digits."""
    return isinstance(text, str) and bool(_HEX_RE.fullmatch(text))
