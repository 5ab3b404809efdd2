"""Who may use the ZeroMQ front: CURVE encryption and authentication by ZeroMQ's own ZAP
(pyzmq's ThreadAuthenticator), and the same roles as over Zenoh (docs/SECURITY.md).

``galton-daemon --zmq-key FILE`` gives the daemon a CURVE key pair (a ``.key_secret`` file
as ``zmq.auth.create_certificates`` writes it, or ``galton-client zmq-keys``). With
``--users``, a client connects only with a CURVE key pair whose public key a user of the
file names (``zmq_public_key``), and its requests carry that user's role: the ZAP handler
sets the connection's User-Id, which each message carries to the physics thread. Without
``--users``, any key pair connects (encryption only), every client an operator.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import zmq
import zmq.auth
from zmq.auth.thread import ThreadAuthenticator

from galton.daemon.access.roles import VIEWER_OPERATIONS, may_ask
from galton.daemon.access.users import User
from galton.protocol import InvalidArgumentError
from galton.protocol.errors import RoleDeniedError

log = logging.getLogger("galton.daemon")
ZAP_DOMAIN = b"galton"


@dataclass(frozen=True)
class ZmqSecurity:
    """The daemon's CURVE key pair and the users allowed in (None: any key)."""

    public_key: bytes
    secret_key: bytes = field(repr=False)
    users: Mapping[str, User] | None = None

    @classmethod
    def load(cls, key_file: Path, users: Mapping[str, User] | None) -> ZmqSecurity:
        """Read the key pair, refusing a file that holds no secret key by name."""
        try:
            public, secret = zmq.auth.load_certificate(str(key_file))
        except (OSError, ValueError) as error:
            raise InvalidArgumentError(
                f"--zmq-key {str(key_file)!r} is not a ZeroMQ key pair: {error} (make one "
                "with `galton-client zmq-keys DIR`)") from error
        if not secret:
            raise InvalidArgumentError(
                f"--zmq-key {str(key_file)!r} holds a public key only: give the "
                ".key_secret file")
        return cls(public, secret, users)

    def role_of(self, user_id: str) -> str | None:
        """The role of a connection's User-Id (None without --users: no roles)."""
        if self.users is None:
            return None
        user = self.users.get(user_id)
        return user.role if user is not None else "none"

    def secure(self, socket: zmq.Socket[bytes]) -> None:
        """Make a socket a CURVE server of this key pair, authenticated by our ZAP domain."""
        socket.curve_secretkey = self.secret_key
        socket.curve_publickey = self.public_key
        socket.curve_server = True
        socket.zap_domain = ZAP_DOMAIN


class UsersByKey:
    """pyzmq's credentials provider: a key is let in if a user of the file names it."""

    def __init__(self, users: Mapping[str, User]) -> None:
        self.by_key = {user.zmq_public_key.encode(): user for user in users.values()
                       if user.zmq_public_key}

    def callback(self, domain: str, key: bytes) -> bool:
        return key in self.by_key


class KeyAuthenticator(ThreadAuthenticator):
    """The ZAP handler (its own thread, asked once per connection, never per message):
    a connection's User-Id is its user's name."""

    def __init__(self, context: zmq.Context[zmq.Socket[bytes]], security: ZmqSecurity) -> None:
        super().__init__(context, log=log)
        self.provider = UsersByKey(security.users) if security.users is not None else None

    def curve_user_id(self, client_public_key: bytes) -> str:
        if self.provider is None:
            return ""
        return self.provider.by_key[zmq.utils.z85.encode(client_public_key)].name


def start_authenticator(context: zmq.Context[zmq.Socket[bytes]],
                        security: ZmqSecurity) -> KeyAuthenticator:
    authenticator = KeyAuthenticator(context, security)
    authenticator.start()
    if authenticator.provider is None:
        authenticator.configure_curve(domain=ZAP_DOMAIN.decode(),
                                      location=zmq.auth.CURVE_ALLOW_ANY)
    else:
        authenticator.configure_curve_callback(domain=ZAP_DOMAIN.decode(),
                                               credentials_provider=authenticator.provider)
    return authenticator


def refuse_by_role(role: str | None, op: str) -> None:
    """Refuse a request its sender's role may not ask: viewers ask only the operations
    declared ``viewer=True`` (protocol/operations.py), as over Zenoh
    (daemon/access/zenoh_security.py); a key no user names gets nothing."""
    if may_ask(role, op):
        return
    raise RoleDeniedError(
        f"{op}: this client's role ({role}) may not ask it; a viewer may ask "
        f"{', '.join(VIEWER_OPERATIONS)} only", {"role": role})
