"""How ``--zenoh-config FILE`` and the daemon's own options make one Zenoh configuration.

The rules, in order (docs/protocol.md, "Transport"):

1. What the command line gives explicitly wins: ``--listen``, ``--connect``,
   ``--multicast``, and the values of ``--users`` and ``--tls-*``.
2. Else what the file says: its mode, endpoints and scouting are honoured.
3. Else the daemon's defaults: a peer listening on ``tcp/127.0.0.1:7460`` with multicast
   scouting off (Zenoh's own defaults would listen on every interface and scout).

A file that sets access control or a usrpwd dictionary together with ``--users`` is
refused: two sources for who may do what would leave one silently ignored.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

import zenoh

from galton.daemon.access.zenoh_security import TLS_SCHEME, USRPWD
from galton.protocol import DEFAULT_PORT
from galton.protocol.errors import InvalidArgumentError

DEFAULT_LISTEN = f"tcp/127.0.0.1:{DEFAULT_PORT}"
DEFAULT_TLS_LISTEN = f"tls/127.0.0.1:{DEFAULT_PORT + 1}"
MODE = "mode"
LISTEN = "listen/endpoints"
CONNECT = "connect/endpoints"
MULTICAST = "scouting/multicast/enabled"
ACL_ENABLED = "access_control/enabled"
MERGED_KEYS = (MODE, LISTEN, CONNECT, MULTICAST, ACL_ENABLED, USRPWD)


def file_says(config: zenoh.Config) -> dict[str, Any]:
    """The file's value of each key the daemon merges, None where the file is silent (its
    value is Zenoh's built-in default: the mode-dependent listen map nobody writes by hand,
    null for the mode and multicast, no connect endpoint)."""
    defaults = zenoh.Config()
    said: dict[str, Any] = {}
    for key in MERGED_KEYS:
        value = json.loads(config.get_json(key))
        said[key] = None if value == json.loads(defaults.get_json(key)) else value
    return said


def merge(said: Mapping[str, Any], listen: list[str], connect: list[str], multicast: bool,
          security: Mapping[str, Any]) -> dict[str, Any]:
    """The values to insert into the file's configuration (key path to value), by the rules
    of the module's docstring. ``security`` holds what ``--users`` / ``--tls-*`` set."""
    _refuse_two_sources(said, security)
    inserts: dict[str, Any] = {}
    if said.get(MODE) is None:
        inserts[MODE] = "peer"
    if multicast or said.get(MULTICAST) is None:
        inserts[MULTICAST] = multicast
    endpoints = listen or said.get(LISTEN) or [DEFAULT_LISTEN]
    if isinstance(endpoints, list) and any(k.startswith("transport/link/tls/") for k in security):
        endpoints = _with_tls_endpoint(endpoints)
    if endpoints != said.get(LISTEN):
        inserts[LISTEN] = endpoints
    if connect:
        inserts[CONNECT] = connect
    inserts.update(security)
    return inserts


def _with_tls_endpoint(endpoints: list[Any]) -> list[Any]:
    """TLS options without a ``tls/`` endpoint to listen on add one on loopback."""
    if any(str(e).startswith(TLS_SCHEME) for e in endpoints):
        return endpoints
    return [*endpoints, DEFAULT_TLS_LISTEN]


def _refuse_two_sources(said: Mapping[str, Any], security: Mapping[str, Any]) -> None:
    if "access_control" in security and said.get(ACL_ENABLED):
        raise InvalidArgumentError(
            "--users and the --zenoh-config file both set access control: keep one (the "
            "file's access_control, or --users)")
    if USRPWD in security and said.get(USRPWD) is not None:
        raise InvalidArgumentError(
            "--users and the --zenoh-config file both name a usrpwd dictionary: keep one")


def listen_endpoints(config: zenoh.Config) -> list[str]:
    """The endpoints a configuration listens on (for the readiness line)."""
    value = json.loads(config.get_json(LISTEN))
    return [str(e) for e in value] if isinstance(value, list) else []
