"""Zenoh key expressions of one daemon instance.

Control queryables live under a chunk that starts with ``@`` so that a broad wildcard get
(``galton/**``) can never reach them: Zenoh matches ``@`` chunks only verbatim.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from galton.protocol.errors import InvalidArgumentError

ROOT = "galton"
DEFAULT_PORT = 7460
CONTROL_CHUNK = "@ctl"
ALIVE_CHUNK = "alive"
LIVELINESS_PATTERN = f"{ROOT}/*/{ALIVE_CHUNK}"
# Every SDK client holds a liveliness token here; a daemon watches them, so that a long step
# asked by a client that has gone is not run to its end for nobody.
CLIENTS_CHUNK = "_clients"
CLIENTS_PATTERN = f"{ROOT}/{CLIENTS_CHUNK}/*"
# A viewer's client id starts so (galton-client view): under --users a viewer may hold such a
# token, and only such, so that its state streams end when it goes (docs/SECURITY.md).
VIEWER_ID_PREFIX = "viewer-"
STREAMS_CHUNK = "states"  # state streams publish on galton/<instance>/states/<stream id>


def client_token_key(client_id: str) -> str:
    """The liveliness key of one client, ``galton/_clients/<client id>``."""
    return f"{ROOT}/{CLIENTS_CHUNK}/{client_id}"


def client_from_token_key(key: str) -> str | None:
    parts = key.split("/")
    if len(parts) == 3 and parts[0] == ROOT and parts[1] == CLIENTS_CHUNK:
        return parts[2]
    return None

_INSTANCE_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.\-]{0,63}$")


def validate_instance_name(name: str) -> str:
    """Instance names are one key chunk: letters, digits, '_', '-', '.' (not first), ≤ 64."""
    if not isinstance(name, str) or not _INSTANCE_RE.fullmatch(name):
        raise InvalidArgumentError(
            f"instance name {name!r} is not valid: use 1-64 letters, digits, '_', '-' or '.', "
            "not starting with '-' or '.'"
        )
    return name


@dataclass(frozen=True)
class Keys:
    """Every key expression that belongs to one instance."""

    instance: str

    def __post_init__(self) -> None:
        validate_instance_name(self.instance)

    @property
    def prefix(self) -> str:
        return f"{ROOT}/{self.instance}"

    @property
    def control_all(self) -> str:
        """What the daemon's queryable is declared on."""
        return f"{self.prefix}/{CONTROL_CHUNK}/*"

    def control(self, op: str) -> str:
        """Where a client sends operation ``op``."""
        return f"{self.prefix}/{CONTROL_CHUNK}/{op}"

    @property
    def telemetry(self) -> str:
        return f"{self.prefix}/telemetry"

    @property
    def events(self) -> str:
        return f"{self.prefix}/events"

    @property
    def alive(self) -> str:
        """The daemon's liveliness token."""
        return f"{self.prefix}/{ALIVE_CHUNK}"


def instance_from_liveliness_key(key: str) -> str | None:
    """The instance named by a liveliness key ``galton/<instance>/alive``, else None."""
    parts = key.split("/")
    if len(parts) == 3 and parts[0] == ROOT and parts[2] == ALIVE_CHUNK:
        return parts[1]
    return None


def op_from_control_key(key: str) -> str:
    """The operation name, the last chunk of ``galton/<instance>/@ctl/<op>``."""
    return key.rsplit("/", 1)[-1]
