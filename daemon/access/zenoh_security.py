"""The Zenoh side of ``--users`` and ``--tls-*``: authentication, access control and TLS as
Zenoh configuration values (docs/SECURITY.md).

Access control denies by default and allows each role only what it needs, rule by rule
and **direction by direction**: a rule allowing ``put`` both ways would let a viewer
publish forged telemetry through the daemon, and one allowing ``declare_queryable`` or
``reply`` inbound would let it answer requests in the daemon's name.

=========  ===========================================================================
role       allowed
=========  ===========================================================================
operator   in: query ``@ctl/*``, subscribe telemetry and events, discovery
           (liveliness get and subscribe on ``galton/*/alive``), a client token under
           ``galton/_clients/*`` (any id: the lease trusts operators). out: replies,
           telemetry, events, daemon tokens, the daemon's control queryable (a querier
           asks only where one is declared)
viewer     in: query ``@ctl/<op>`` for the operations declared ``viewer=True``
           (protocol/operations.py: status, capabilities and the read-only operations of
           ``galton-client view``), subscribe telemetry, events and state streams,
           discovery. out: those replies, telemetry, events, daemon tokens, the
           daemon's control queryable
=========  ===========================================================================

Nobody may put, delete, reply or declare a queryable inbound on any key.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from galton.daemon.access.roles import VIEWER_OPERATIONS
from galton.daemon.access.users import OPERATOR, ROLES, VIEWER, User, by_role
from galton.protocol import Keys
from galton.protocol.errors import InvalidArgumentError
from galton.protocol.keys import (
    CLIENTS_PATTERN,
    LIVELINESS_PATTERN,
    STREAMS_CHUNK,
    VIEWER_ID_PREFIX,
    client_token_key,
)

TLS_SCHEME = "tls/"
USRPWD = "transport/auth/usrpwd/dictionary_file"


@dataclass(frozen=True)
class TlsFiles:
    """The daemon's TLS certificate and key, and the CA its clients' certificates must be
    signed by (given: mutual TLS, roles by certificate common name)."""

    cert: Path
    key: Path
    ca: Path | None = None

    def __post_init__(self) -> None:
        for what, path in (("--tls-cert", self.cert), ("--tls-key", self.key),
                           ("--tls-ca", self.ca)):
            if path is not None and not Path(path).is_file():
                raise InvalidArgumentError(f"{what} {str(path)!r} is not a readable file")

    @property
    def mutual(self) -> bool:
        return self.ca is not None


def tls_settings(tls: TlsFiles) -> dict[str, Any]:
    """Zenoh's ``transport/link/tls`` values for a listening daemon."""
    settings: dict[str, Any] = {
        "transport/link/tls/listen_certificate": str(Path(tls.cert).resolve()),
        "transport/link/tls/listen_private_key": str(Path(tls.key).resolve()),
        "transport/link/tls/enable_mtls": tls.mutual,
    }
    if tls.ca is not None:
        settings["transport/link/tls/root_ca_certificate"] = str(Path(tls.ca).resolve())
    return settings


def _rule(rule_id: str, flow: str, messages: list[str], keys: list[str]) -> dict[str, Any]:
    return {"id": rule_id, "flows": [flow], "permission": "allow", "messages": messages,
            "key_exprs": keys}


def acl_rules(instance: str) -> list[dict[str, Any]]:
    """Every rule any role uses, for the daemon of ``instance``."""
    keys = Keys(instance)
    watched = [keys.telemetry, keys.events, f"{keys.prefix}/{STREAMS_CHUNK}/*"]
    readonly = [keys.control(op) for op in VIEWER_OPERATIONS]
    return [
        _rule("watch", "ingress", ["declare_subscriber"], watched),
        _rule("discover", "ingress", ["liveliness_query", "declare_liveliness_subscriber"],
              [LIVELINESS_PATTERN]),
        _rule("ask-readonly", "ingress", ["query"], readonly),
        _rule("ask-control", "ingress", ["query"], [keys.control_all]),
        _rule("client-token", "ingress", ["liveliness_token"], [CLIENTS_PATTERN]),
        # A viewer's token says when its state streams end; named apart from any operator's
        # (an SDK id is hex), it can keep no operator's lease alive.
        _rule("viewer-token", "ingress", ["liveliness_token"],
              [client_token_key(f"{VIEWER_ID_PREFIX}$*")]),
        _rule("publish", "egress", ["put"], watched),
        _rule("announce", "egress", ["liveliness_token"], [LIVELINESS_PATTERN]),
        # A Zenoh querier sends nothing once it believes no queryable matches its key.
        _rule("route-control", "egress", ["declare_queryable"], [keys.control_all]),
        _rule("answer-readonly", "egress", ["reply"], readonly),
        _rule("answer-control", "egress", ["reply"], [keys.control_all]),
    ]


ROLE_RULES = {
    OPERATOR: ["watch", "discover", "ask-control", "client-token", "publish", "announce",
               "route-control", "answer-control"],
    VIEWER: ["watch", "discover", "ask-readonly", "viewer-token", "publish", "announce",
             "route-control", "answer-readonly"],
}


def role_subjects(users: Mapping[str, User], role: str,
                  by_certificate: bool) -> list[dict[str, Any]]:
    """The subjects of one role: its users by name (password), and by certificate common
    name with mutual TLS. A subject's lists are never empty (Zenoh refuses those)."""
    members = by_role(users, role)
    names = [u.name for u in members if u.secret is not None]
    certificates = [u.tls_name for u in members if u.tls_name is not None]
    subjects = []
    if names:
        subjects.append({"id": f"{role}-users", "usernames": names})
    if by_certificate and certificates:
        subjects.append({"id": f"{role}-certificates", "cert_common_names": certificates})
    return subjects


def access_control(users: Mapping[str, User], instance: str,
                   by_certificate: bool = False) -> dict[str, Any]:
    """Zenoh's ``access_control`` section: default deny, each role its rules."""
    subjects: list[dict[str, Any]] = []
    policies: list[dict[str, Any]] = []
    for role in ROLES:
        found = role_subjects(users, role, by_certificate)
        if found:
            subjects += found
            policies.append({"id": role, "rules": ROLE_RULES[role],
                             "subjects": [s["id"] for s in found]})
    return {"enabled": True, "default_permission": "deny", "rules": acl_rules(instance),
            "subjects": subjects, "policies": policies}


def uses_passwords(users: Mapping[str, User]) -> bool:
    """Whether Zenoh's user/password check is on: it is as soon as one user has one."""
    return any(user.secret is not None for user in users.values())


def check_reachable(users: Mapping[str, User], by_certificate: bool) -> None:
    """Refuse a users file where a user could never use Zenoh: the password check applies
    to every link, so a certificate-only user beside password users could not connect."""
    if not uses_passwords(users):
        return
    for user in users.values():
        if user.secret is None and user.tls_name is not None and by_certificate:
            raise InvalidArgumentError(
                f"user {user.name!r} has a tls_name but no password while other users have "
                "passwords: Zenoh's password check applies to every link, TLS included, so "
                f"{user.name!r} could not connect; give it a password too")


def dictionary_text(users: Mapping[str, User]) -> str:
    """Zenoh's usrpwd dictionary: one ``user:wire password`` line per user with one."""
    return "".join(f"{u.name}:{u.secret}\n" for u in users.values() if u.secret is not None)


def write_private_file(text: str, prefix: str = "galton-usrpwd-") -> Path:
    """``text`` in a new file only this user can read (0600). The daemon removes it as soon
    as its session is open (``remove_private_files``: Zenoh reads it only then), and at
    exit in any case."""
    handle, name = tempfile.mkstemp(prefix=prefix, suffix=".txt")
    path = Path(name)
    os.fchmod(handle, 0o600)
    with os.fdopen(handle, "w", encoding="utf-8") as stream:
        stream.write(text)
    atexit.register(_remove, path)
    _PRIVATE_FILES.append(path)
    return path


_PRIVATE_FILES: list[Path] = []


def remove_private_files() -> None:
    """Remove every private file written so far: once its session is open, Zenoh has read
    the dictionary and needs it no more, so nothing is left for a SIGKILL to strand."""
    while _PRIVATE_FILES:
        _remove(_PRIVATE_FILES.pop())


def _remove(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()


def security_settings(users: Mapping[str, User] | None, tls: TlsFiles | None,
                      instance: str) -> dict[str, Any]:
    """Every Zenoh config value ``--users`` and ``--tls-*`` set, as key path to value;
    writes the usrpwd dictionary to a private file when a user has a password."""
    settings: dict[str, Any] = tls_settings(tls) if tls is not None else {}
    if users is None:
        return settings
    by_certificate = tls is not None and tls.mutual
    check_reachable(users, by_certificate)
    settings["access_control"] = access_control(users, instance, by_certificate)
    if uses_passwords(users):
        settings[USRPWD] = str(write_private_file(dictionary_text(users)))
    return settings
