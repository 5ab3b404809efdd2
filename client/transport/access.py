"""Telling "access denied" from "not reachable": Zenoh says neither in words.

What a refusal looks like to a client, found by experiment with zenoh 1.10.2 on loopback
(tests/daemon/access/test_security_zenoh.py shows each):

- A daemon started with ``--users`` closes a session that brings no credentials, a wrong
  password or an unknown user during the handshake, and a TLS handshake fails when either
  side's certificate was signed by a CA the other does not trust. Either way
  ``zenoh.open`` raises the same ``ZError`` as for a port where nothing listens. A plain
  TCP connection to the endpoint tells them apart: if something accepts it, the session
  was refused, not unanswered.
- A request the client's role may not make is dropped by the daemon's access control:
  the get ends **at once** with no reply (a busy daemon's ends at its timeout), while the
  daemon's liveliness token stays visible.
"""

from __future__ import annotations

import re
import socket
from collections.abc import Sequence

from galton.client.transport.credentials import Credentials
from galton.protocol.errors import AccessDeniedError, DaemonUnreachableError, GaltonError

PROBE_TIMEOUT_S = 1.0
# A get with no reply that ended before this fraction of its timeout was refused (a
# refused get ends in well under a millisecond on loopback; a silent daemon's at timeout).
REFUSED_BEFORE = 0.5
PROBED_SCHEMES = ("tcp/", "tls/")
SECURITY_DOC = "docs/SECURITY.md"


def host_and_port(endpoint: str) -> tuple[str, int] | None:
    """The host and port of a ``tcp/HOST:PORT`` or ``tls/HOST:PORT`` endpoint, else None."""
    scheme = next((s for s in PROBED_SCHEMES if endpoint.startswith(s)), None)
    if scheme is None:
        return None
    address = endpoint[len(scheme):].split("?", 1)[0].split("#", 1)[0]
    host, _, port = address.rpartition(":")
    if not host or not port.isdigit():
        return None
    return host.strip("[]"), int(port)


def listening(endpoint: str, timeout: float = PROBE_TIMEOUT_S) -> bool:
    """Whether something accepts a TCP connection at the endpoint now."""
    address = host_and_port(endpoint)
    if address is None:
        return False
    try:
        with socket.create_connection(address, timeout=timeout):
            return True
    except OSError:
        return False


def session_refused(endpoints: Sequence[str], credentials: Credentials | None,
                    error: Exception) -> GaltonError:
    """The error a failed ``zenoh.open`` means: AccessDeniedError when something listens
    at an endpoint (the daemon refused the session), else DaemonUnreachableError."""
    detail = _scrubbed(str(error), credentials)
    answering = [endpoint for endpoint in endpoints if listening(endpoint)]
    if not answering:
        return DaemonUnreachableError(
            f"no Zenoh peer answers at {', '.join(endpoints)}: is galton-daemon running "
            f"there? (start one with `galton-daemon --listen {endpoints[0]}`) [{detail}]")
    who = credentials.describe() if credentials is not None else "no credentials"
    return AccessDeniedError(
        f"a daemon listens at {answering[0]} but refused this session ({who}): "
        f"{_refusal_hint(credentials)} (see {SECURITY_DOC})")


def _refusal_hint(credentials: Credentials | None) -> str:
    if credentials is None:
        return ("it needs credentials: --user with --password-file (or GALTON_USER and "
                "GALTON_PASSWORD), or TLS files")
    hints = []
    if credentials.user is not None:
        hints.append("a wrong password, a user its users file does not name, or a daemon "
                     "without --users (it refuses any user: connect without one)")
    if credentials.tls_cert is not None:
        hints.append("a client certificate signed by a CA it does not trust")
    elif credentials.tls_ca is not None:
        hints.append("it may ask for a client certificate (--tls-cert and --tls-key)")
    if credentials.tls_ca is not None:
        hints.append("a daemon certificate that --tls-ca did not sign")
    return "; or ".join(hints) or "it needs other credentials"


# Where in its Rust source Zenoh raised an error: " at /root/.cargo/.../orchestrator.rs:447."
_RUST_SOURCE = re.compile(r"\s+at \S+\.rs:\d+\.?")


def _scrubbed(text: str, credentials: Credentials | None) -> str:
    """Zenoh's message without its Rust source path (noise to a user) and with any secret
    of ours cut out (none is expected in it)."""
    text = _RUST_SOURCE.sub("", text).strip()
    if credentials is None:
        return text
    for secret in (credentials.password, credentials.wire_password):
        if secret:
            text = text.replace(secret, "***")
    return text


def refused_at_once(elapsed: float, wait: float) -> bool:
    """Whether a get that brought no reply from a visible daemon was refused by its access
    control (it ended early) rather than left unanswered (it ran to its timeout)."""
    return elapsed < REFUSED_BEFORE * wait


def access_denied(op: str, instance: str) -> AccessDeniedError:
    return AccessDeniedError(
        f"{op}: daemon {instance!r} is there but refused this request at once: this "
        f"client's role may not ask {op!r} (a viewer may ask status and capabilities "
        f"only; see {SECURITY_DOC})")
