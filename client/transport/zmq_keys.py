"""A ZeroMQ client's CURVE keys, and what a first connection's handshake says.

A daemon started with ``--zmq-key`` speaks CURVE on its ZeroMQ front: a client needs its
own key pair (a ``.key_secret`` file, ``galton-client zmq-keys DIR`` makes one) and the
daemon's public key (its ``.key`` file, or the Z85 text ``capabilities`` shows as
``zmq.server_key``). With ``--users``, the client's public key must be a user's
``zmq_public_key``; a refused key fails the handshake, which is told apart from an absent
daemon by watching the socket's handshake events (docs/SECURITY.md, "ZeroMQ").
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import zmq
import zmq.auth
import zmq.utils.z85
from zmq.utils.monitor import parse_monitor_message

from galton.protocol import AccessDeniedError, DaemonUnreachableError, InvalidArgumentError

KEY_ENV = "GALTON_ZMQ_KEY"
SERVER_KEY_ENV = "GALTON_ZMQ_SERVER_KEY"
Z85_KEY_LENGTH = 40
HANDSHAKE_EVENTS = (zmq.EVENT_HANDSHAKE_SUCCEEDED | zmq.EVENT_HANDSHAKE_FAILED_AUTH
                    | zmq.EVENT_HANDSHAKE_FAILED_PROTOCOL
                    | zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL)


@dataclass(frozen=True)
class ZmqKeys:
    """This client's CURVE key pair and the daemon's public key (Z85 bytes)."""

    public_key: bytes
    secret_key: bytes = field(repr=False)
    server_key: bytes

    @classmethod
    def load(cls, key_file: str | Path, server_key: str | Path) -> ZmqKeys:
        """Read a ``.key_secret`` file, and the server key as Z85 text or a key file."""
        public, secret = _read_pair(Path(key_file), "the client key")
        if not secret:
            raise InvalidArgumentError(
                f"the client key {str(key_file)!r} holds a public key only: give its "
                ".key_secret file")
        text = str(server_key)
        if len(text) == Z85_KEY_LENGTH and not Path(text).exists():
            return cls(public, secret, _z85_key(text))
        server_public, _ = _read_pair(Path(text), "the daemon's key")
        return cls(public, secret, server_public)

    @classmethod
    def from_env(cls) -> ZmqKeys | None:
        """From GALTON_ZMQ_KEY and GALTON_ZMQ_SERVER_KEY, when both are set."""
        key, server = os.environ.get(KEY_ENV), os.environ.get(SERVER_KEY_ENV)
        if not key and not server:
            return None
        if not key or not server:
            raise InvalidArgumentError(f"set both {KEY_ENV} and {SERVER_KEY_ENV}, or neither")
        return cls.load(key, server)

    def apply(self, socket: zmq.Socket[bytes]) -> None:
        """Make a socket a CURVE client of the daemon (before it connects)."""
        socket.curve_publickey = self.public_key
        socket.curve_secretkey = self.secret_key
        socket.curve_serverkey = self.server_key


def _z85_key(text: str) -> bytes:
    """A daemon's public key given as Z85 text, checked (libzmq says only "Invalid
    argument" when the socket is given it)."""
    try:
        zmq.utils.z85.decode(text.encode())
    except (KeyError, ValueError):
        raise InvalidArgumentError(
            f"the daemon's key {text!r} is not a Z85 CURVE public key: give the 40 characters "
            "capabilities shows as zmq.server_key, or the daemon's .key file") from None
    return text.encode()


def _read_pair(path: Path, what: str) -> tuple[bytes, bytes | None]:
    try:
        return zmq.auth.load_certificate(str(path))
    except (OSError, ValueError) as error:
        raise InvalidArgumentError(
            f"{what} {str(path)!r} is not a ZeroMQ key file: {error} (make one with "
            "`galton-client zmq-keys DIR`)") from error


def wait_for_handshake(socket: zmq.Socket[bytes], monitor: zmq.Socket[bytes],
                       endpoint: str, timeout: float) -> None:
    """Wait until ``socket`` may send (connected and, with CURVE, let in); a refused
    handshake raises AccessDeniedError, silence DaemonUnreachableError."""
    poller = zmq.Poller()
    poller.register(socket, zmq.POLLOUT)
    poller.register(monitor, zmq.POLLIN)
    deadline = time.monotonic() + timeout
    while (remaining := deadline - time.monotonic()) > 0:
        ready = dict(poller.poll(max(1, int(remaining * 1000))))
        if socket in ready:
            return
        if monitor in ready:
            event = parse_monitor_message(monitor.recv_multipart())["event"]
            if event != zmq.EVENT_HANDSHAKE_SUCCEEDED:
                raise AccessDeniedError(
                    f"the daemon at {endpoint} refused this client's handshake: "
                    f"{_why(event)}")
    raise DaemonUnreachableError(
        f"no galton-daemon answers at {endpoint} (start one with `galton-daemon --zmq "
        f"{endpoint}`)")


def _why(event: int) -> str:
    if event == zmq.EVENT_HANDSHAKE_FAILED_AUTH:
        return ("its CURVE key is not a user's (the daemon's --users file names each user's "
                "zmq_public_key)")
    return ("the daemon speaks CURVE and this client does not, or the other way round "
            "(give the client key and the daemon's public key: --zmq-key and "
            "--zmq-server-key)")
