"""Issue 28 on the ZeroMQ front, against a real daemon: ``--zmq-key`` (CURVE) with
``--users`` (each user's ``zmq_public_key`` and role). docs/SECURITY.md's table names each
test. "Nothing arrived" is checked after a later message on the same link has arrived."""

from __future__ import annotations

import os
import queue
import stat
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest
import zmq
import zmq.auth

from galton.client import (
    AccessDeniedError,
    Client,
    EmbeddedDaemon,
    InvalidArgumentError,
    RoleDeniedError,
    spheres,
)
from galton.client.sdk.embedded import daemon_command, free_loopback_port
from galton.client.transport.zmq_keys import ZmqKeys

USERS = """
[users.alice]
role = "operator"
password = "alice-secret-1"
zmq_public_key = "{alice}"

[users.bob]
role = "viewer"
password = "bob-secret-2"
zmq_public_key = "{bob}"
"""
WAIT_S = 20.0


class Keys:
    """Key pairs made by pyzmq: the daemon's, two users' and a stranger's."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        for name in ("daemon", "alice", "bob", "stranger"):
            zmq.auth.create_certificates(str(folder), name)

    def public(self, name: str) -> str:
        return zmq.auth.load_certificate(str(self.folder / f"{name}.key"))[0].decode()

    def secret_file(self, name: str) -> Path:
        return self.folder / f"{name}.key_secret"

    def client(self, name: str, server: str = "daemon") -> ZmqKeys:
        return ZmqKeys.load(self.secret_file(name), self.folder / f"{server}.key")


@pytest.fixture(scope="module")
def keys(tmp_path_factory: pytest.TempPathFactory) -> Keys:
    return Keys(tmp_path_factory.mktemp("zmq-keys"))


@pytest.fixture(scope="module")
def secured(keys: Keys, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Path]]:
    folder = tmp_path_factory.mktemp("zmq-secured")
    users = folder / "users.toml"
    users.write_text(USERS.format(alice=keys.public("alice"), bob=keys.public("bob")))
    users.chmod(0o600)
    socket_file = folder / "control.sock"
    with EmbeddedDaemon("mujoco", instance="zmq-secured", telemetry_rate=50.0, extra_args=[
            "--users", str(users), "--zmq", f"ipc://{socket_file}",
            "--zmq-key", str(keys.secret_file("daemon"))]):
        yield f"zmq+ipc://{socket_file}", socket_file


@pytest.fixture
def operator(secured: tuple[str, Path], keys: Keys) -> Iterator[Client]:
    with Client(connect=secured[0], zmq_keys=keys.client("alice"), timeout=20) as client:
        client.load_world("mujoco")
        yield client


def test_no_key_a_stranger_s_key_or_a_wrong_daemon_key_is_refused(
        secured: tuple[str, Path], keys: Keys) -> None:
    with pytest.raises(AccessDeniedError, match="speaks CURVE"):
        Client(connect=secured[0])
    with pytest.raises(AccessDeniedError, match="not a user's"):
        Client(connect=secured[0], zmq_keys=keys.client("stranger"))
    with pytest.raises(AccessDeniedError):
        Client(connect=secured[0], zmq_keys=keys.client("alice", server="stranger"))


def test_a_server_key_that_is_no_z85_key_is_a_typed_error(keys: Keys) -> None:
    """40 characters that are no Z85 key used to reach libzmq, which said only "Invalid
    argument" (a bare ZMQError) when the socket was made."""
    with pytest.raises(InvalidArgumentError, match="not a Z85 CURVE public key"):
        ZmqKeys.load(keys.secret_file("alice"), '"' * 40)


def test_a_viewer_reads_status_and_telemetry_but_cannot_change_the_world(
        operator: Client, secured: tuple[str, Path], keys: Keys) -> None:
    with Client(connect=secured[0], zmq_keys=keys.client("bob")) as viewer:
        assert viewer.status().instance == "zmq-secured"
        assert viewer.capabilities().zmq["server_key"] == keys.public("daemon")
        with viewer.telemetry(timeout=WAIT_S) as stream:
            assert next(stream).instance == "zmq-secured"
        for attempt in (lambda: viewer.spawn(spheres(["b"], [[0, 0, 1]], 0.1)),
                        lambda: viewer.step(10), lambda: viewer.reset("all"),
                        lambda: viewer.set_params({"timestep": 0.01}),
                        viewer.take_control):
            with pytest.raises(RoleDeniedError, match="viewer"):
                attempt()
    assert operator.list() == [] and operator.status().step == 0
    assert operator.get_params()["timestep"] != 0.01


def test_an_operator_can_do_everything(operator: Client) -> None:
    operator.spawn(spheres(["b"], [[0, 0, 1]], 0.1))
    assert operator.step_and_read(10, ["b"]).step == 10
    with operator.control():
        operator.reset("all")
    assert operator.list() == []


def test_a_stranger_s_subscription_receives_nothing(operator: Client,
                                                    secured: tuple[str, Path],
                                                    keys: Keys) -> None:
    """The PUB socket speaks CURVE too: a stranger's SUB handshake fails, so while the
    operator receives samples the stranger's socket stays empty."""
    telemetry = operator.capabilities().zmq["telemetry"][0]
    context = zmq.Context()
    try:
        stranger = context.socket(zmq.SUB)
        keys.client("stranger").apply(stranger)
        monitor = stranger.get_monitor_socket(zmq.EVENT_HANDSHAKE_FAILED_AUTH)
        stranger.connect(telemetry)
        stranger.subscribe(b"")
        assert monitor.poll(WAIT_S * 1000), "the stranger's handshake was not refused"
        seen: queue.Queue[object] = queue.Queue()
        with operator.on_telemetry(seen.put):
            for _ in range(3):
                seen.get(timeout=WAIT_S)
        assert stranger.poll(0) == 0
    finally:
        context.destroy(linger=0)


def test_the_socket_files_are_not_open_to_other_users(secured: tuple[str, Path]) -> None:
    for path in (secured[1], Path(f"{secured[1]}.pub")):
        assert stat.S_IMODE(os.stat(path).st_mode) & 0o007 == 0, oct(os.stat(path).st_mode)


def test_users_with_zmq_but_no_key_is_refused_at_start(tmp_path: Path, keys: Keys) -> None:
    users = tmp_path / "users.toml"
    users.write_text(USERS.format(alice=keys.public("alice"), bob=keys.public("bob")))
    users.chmod(0o600)
    done = subprocess.run([*daemon_command(), "--users", str(users), "--zmq",
                           f"ipc://{tmp_path}/s.sock", "--listen",
                           f"tcp/127.0.0.1:{free_loopback_port()}"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "needs --zmq-key" in done.stderr, done.stderr


def test_a_key_without_users_encrypts_and_lets_any_key_in(keys: Keys, tmp_path: Path) -> None:
    socket_file = tmp_path / "open.sock"
    with EmbeddedDaemon("mujoco", instance="zmq-encrypted", extra_args=[
            "--zmq", f"ipc://{socket_file}", "--zmq-key", str(keys.secret_file("daemon"))]):
        with pytest.raises(AccessDeniedError, match="speaks CURVE"):
            Client(connect=f"zmq+ipc://{socket_file}")
        with Client(connect=f"zmq+ipc://{socket_file}",
                    zmq_keys=keys.client("stranger")) as anyone:
            anyone.load_world("mujoco")
            assert anyone.spawn(spheres(["b"], [[0, 0, 1]], 0.1)) == ["b"]


def test_zmq_keys_writes_a_pair_and_overwrites_no_key(tmp_path: Path) -> None:
    """``galton-client zmq-keys`` used to check only NAME.key_secret, and replaced a NAME.key
    already there (say the daemon's public key, copied beside the client's keys)."""
    from support.cli import run

    result = run(["zmq-keys", str(tmp_path / "mine")])
    assert result.exit_code == 0, result.output
    public = zmq.auth.load_certificate(str(tmp_path / "mine" / "galton.key"))[0].decode()
    assert f'zmq_public_key = "{public}"' in result.stdout
    assert stat.S_IMODE(os.stat(tmp_path / "mine" / "galton.key_secret").st_mode) == 0o600
    daemon_key = tmp_path / "theirs" / "galton.key"
    daemon_key.parent.mkdir()
    daemon_key.write_text("the daemon's public key")
    result = run(["zmq-keys", str(daemon_key.parent)])
    assert result.exit_code != 0 and "nothing was overwritten" in result.output, result.output
    assert daemon_key.read_text() == "the daemon's public key"
    assert not (daemon_key.parent / "galton.key_secret").exists()
