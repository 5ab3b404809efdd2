"""The users file of ``galton-daemon --users FILE``: who may connect, and in which role.

A TOML file with one table per user::

    [users.alice]
    role = "operator"              # "operator": every operation; "viewer": watch only
    password_sha256 = "<64 hex>"   # `galton-client hash-password alice` prints it
    # password = "clear text"      # instead of password_sha256, for tests and demos
    tls_name = "alice.robot"       # optional: the common name of alice's TLS certificate
    zmq_public_key = "<40 chars>"  # optional: alice's ZeroMQ CURVE public key (Z85)

A user needs at least one credential (a password, a TLS name or a ZeroMQ key). Every bad
entry is refused by name and field, before the daemon serves anything.
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.protocol.auth import is_wire_hash, validate_user_name, wire_password
from galton.protocol.errors import InvalidArgumentError, brief, did_you_mean

OPERATOR = "operator"
VIEWER = "viewer"
ROLES = (OPERATOR, VIEWER)
FIELDS = ("role", "password", "password_sha256", "tls_name", "zmq_public_key")
Z85_ALPHABET = frozenset(
    "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ.-:+=^!/*?&<>()[]{}@%$#")
Z85_KEY_LENGTH = 40  # a 32-byte CURVE key in Z85
TLS_NAME_MAX = 64  # an X.509 common name is at most 64 characters


@dataclass(frozen=True)
class User:
    """One user of the file. ``secret`` is what Zenoh's usrpwd dictionary holds (the wire
    password, password-equivalent), kept out of ``repr`` so that no log shows it."""

    name: str
    role: str
    secret: str | None = field(default=None, repr=False)
    tls_name: str | None = None
    zmq_public_key: str | None = None

    @property
    def operator(self) -> bool:
        return self.role == OPERATOR


def load_users(path: Path | str) -> dict[str, User]:
    """Every user of the file at ``path``, by name; InvalidArgumentError names the first bad
    entry (user and field) or says why the file cannot be read."""
    return parse_users(_read_toml(Path(path)), str(path))


def parse_users(document: Mapping[str, Any], source: str = "the users file") -> dict[str, User]:
    """The users of an already parsed TOML document (see the module's docstring)."""
    extra = sorted(set(document) - {"users"})
    if extra:
        raise InvalidArgumentError(
            f"{source}: unknown top-level key {extra[0]!r}; the file holds [users.NAME] "
            "tables only")
    table = document.get("users")
    if not isinstance(table, dict) or not table:
        raise InvalidArgumentError(
            f"{source} names no users: add a [users.NAME] table with a role and a password "
            "(docs/SECURITY.md)")
    users = {name: parse_user(name, entry, source) for name, entry in table.items()}
    _check_unique(users, "tls_name", source)
    _check_unique(users, "zmq_public_key", source)
    return users


def parse_user(name: str, entry: object, source: str = "the users file") -> User:
    """One ``[users.NAME]`` table as a User."""
    where = f"{source}: user {name!r}"
    try:
        validate_user_name(name)
    except InvalidArgumentError as error:
        raise InvalidArgumentError(f"{source}: {error}") from error
    if not isinstance(entry, dict):
        raise InvalidArgumentError(f"{where} must be a table ([users.{name}]), got {brief(entry)}")
    for key in entry:
        if key not in FIELDS:
            raise InvalidArgumentError(
                f"{where}: unknown field {key!r}{did_you_mean(key, FIELDS)}; fields are "
                f"{', '.join(FIELDS)}")
    user = User(name, _role(entry, where), _secret(name, entry, where),
                _tls_name(entry, where), _zmq_key(entry, where))
    if user.secret is None and user.tls_name is None and user.zmq_public_key is None:
        raise InvalidArgumentError(
            f"{where} has no password: give password_sha256 (or password), tls_name or "
            "zmq_public_key")
    return user


def _read_toml(path: Path) -> dict[str, Any]:
    try:
        with path.open("rb") as stream:
            return tomllib.load(stream)
    except OSError as error:
        raise InvalidArgumentError(
            f"cannot read the users file {str(path)!r}: {error.strerror}") from error
    except tomllib.TOMLDecodeError as error:
        raise InvalidArgumentError(f"the users file {str(path)!r} is not TOML: {error}") from error


def _role(entry: dict[str, Any], where: str) -> str:
    role = entry.get("role")
    if role not in ROLES:
        hint = did_you_mean(role, ROLES) if isinstance(role, str) else ""
        raise InvalidArgumentError(
            f"{where}: role {brief(role)} is not one of {', '.join(ROLES)}{hint}")
    return str(role)


def _secret(name: str, entry: dict[str, Any], where: str) -> str | None:
    """The wire password: from password_sha256 as it is, or hashed from a clear password.
    Neither value is ever quoted in a message."""
    clear, hashed = entry.get("password"), entry.get("password_sha256")
    if clear is not None and hashed is not None:
        raise InvalidArgumentError(f"{where}: give password or password_sha256, not both")
    if hashed is not None:
        if not is_wire_hash(hashed):
            raise InvalidArgumentError(
                f"{where}: password_sha256 must be 64 hex digits (as `galton-client "
                "hash-password` prints it)")
        return str(hashed).lower()
    if clear is not None:
        if not isinstance(clear, str) or not clear:
            raise InvalidArgumentError(f"{where}: password must be a non-empty string")
        return wire_password(name, clear)
    return None


def _tls_name(entry: dict[str, Any], where: str) -> str | None:
    name = entry.get("tls_name")
    if name is None:
        return None
    if not isinstance(name, str) or not name.strip() or len(name) > TLS_NAME_MAX:
        raise InvalidArgumentError(
            f"{where}: tls_name must be a certificate common name of 1-{TLS_NAME_MAX} "
            f"characters, got {brief(name)}")
    return name


def _zmq_key(entry: dict[str, Any], where: str) -> str | None:
    key = entry.get("zmq_public_key")
    if key is None:
        return None
    if not isinstance(key, str) or len(key) != Z85_KEY_LENGTH:
        got = f"{len(key)} characters" if isinstance(key, str) else brief(key)
        raise InvalidArgumentError(
            f"{where}: zmq_public_key must be a CURVE public key in Z85, "
            f"{Z85_KEY_LENGTH} characters (zmq.curve_keypair() makes one), got {got}")
    if not set(key) <= Z85_ALPHABET:
        raise InvalidArgumentError(
            f"{where}: zmq_public_key {key!r} holds characters that are not Z85")
    return key


def _check_unique(users: dict[str, User], attribute: str, source: str) -> None:
    """Two users may not share a certificate name or a ZeroMQ key: a role must follow from
    one credential alone."""
    seen: dict[str, str] = {}
    for user in users.values():
        value = getattr(user, attribute)
        if value is None:
            continue
        if value in seen:
            raise InvalidArgumentError(
                f"{source}: user {user.name!r} has the same {attribute} as user "
                f"{seen[value]!r}: each must be its own")
        seen[value] = user.name


def readable_by_others(path: Path | str) -> bool:
    """Whether accounts other than the owner may read the file: its password hashes are
    password-equivalent for Zenoh, so the daemon warns (docs/SECURITY.md)."""
    return bool(Path(path).stat().st_mode & 0o077)


def by_role(users: Mapping[str, User], role: str) -> list[User]:
    """The users of one role, by name."""
    return sorted((u for u in users.values() if u.role == role), key=lambda u: u.name)
