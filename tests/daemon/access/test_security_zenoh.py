"""Issue 28 on Zenoh, against real daemons on loopback: ``--users`` (user/password and
default-deny access control split by direction) and ``--tls-*`` (mutual TLS, roles by
certificate name). docs/SECURITY.md's table names each test.

Nothing here waits a fixed time: a refusal is seen at once, and "nothing arrived" is
checked after a later message on the same link has (Zenoh keeps one link's order).
"""

from __future__ import annotations

import queue
import threading
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path

import msgpack
import pytest
import zenoh
from support.certs import Certificates, make_certificates
from support.daemons import start_daemon
from support.users import ALICE, BOB, users_file
from typer.testing import CliRunner

from galton.client import (
    AccessDeniedError,
    Client,
    ControlHeldError,
    Credentials,
    DaemonUnreachableError,
    EmbeddedDaemon,
    spheres,
    wait_for_daemon,
)
from galton.client.cli.app import app as cli_app
from galton.client.sdk.embedded import free_loopback_port
from galton.client.transport.session import close_session, daemon_alive, open_session
from galton.protocol import Keys, Reply, ResultCode, encode_reply
from galton.protocol.auth import wire_password

INSTANCE = "secured"
WAIT_S = 20.0
FORGED = b"forged by the viewer"


@pytest.fixture(scope="module")
def secured(tmp_path_factory: pytest.TempPathFactory) -> Iterator[EmbeddedDaemon]:
    """A MuJoCo daemon with --users: alice operates, bob views."""
    folder = tmp_path_factory.mktemp("users")
    with EmbeddedDaemon("mujoco", instance=INSTANCE, telemetry_rate=50.0,
                        extra_args=["--users", str(users_file(folder))]) as daemon:
        yield daemon


@pytest.fixture
def operator(secured: EmbeddedDaemon) -> Iterator[Client]:
    with Client(INSTANCE, secured.endpoint, timeout=WAIT_S, credentials=ALICE) as client:
        client.load_world("mujoco")
        yield client


@pytest.fixture
def viewer(secured: EmbeddedDaemon) -> Iterator[Client]:
    with Client(INSTANCE, secured.endpoint, timeout=WAIT_S, credentials=BOB) as client:
        yield client


# -- no credential, a wrong password, an unknown user --------------------------------------
@pytest.mark.parametrize("credentials", [
    None, Credentials("alice", "not-her-password"), Credentials("carol", "alice-secret-1"),
    Credentials("bob", password_sha256="0" * 64),
], ids=["no-credential", "wrong-password", "unknown-user", "wrong-hash"])
def test_a_session_without_valid_credentials_is_refused(
        secured: EmbeddedDaemon, credentials: Credentials | None) -> None:
    """No session at all: no control, no telemetry, not even the daemon's token."""
    with pytest.raises(AccessDeniedError, match="refused this session") as caught:
        open_session(secured.endpoint, credentials=credentials)
    for secret in ("not-her-password", "alice-secret-1", "0" * 64):
        assert secret not in str(caught.value)
        assert secret not in repr(credentials)


def test_a_refused_session_is_told_apart_from_no_daemon(secured: EmbeddedDaemon) -> None:
    with pytest.raises(DaemonUnreachableError, match="no Zenoh peer answers"):
        open_session(f"tcp/127.0.0.1:{free_loopback_port()}", credentials=ALICE)


def test_a_user_is_refused_by_a_daemon_without_users(
        daemons: dict[str, EmbeddedDaemon]) -> None:
    """Zenoh refuses a password that a daemon does not ask for: the message says so."""
    daemon = start_daemon(daemons, "mujoco")
    with pytest.raises(AccessDeniedError, match="a daemon without --users"):
        open_session(daemon.endpoint, credentials=ALICE)


# -- viewer -------------------------------------------------------------------------------
def test_a_viewer_receives_telemetry_and_reads_status(viewer: Client) -> None:
    with viewer.telemetry(timeout=WAIT_S) as stream:
        assert next(stream).instance == INSTANCE
    assert viewer.status().instance == INSTANCE
    assert viewer.capabilities().engine == "mujoco"
    wait_for_daemon(viewer.session, INSTANCE, WAIT_S)


@pytest.mark.parametrize("action", ["spawn", "step", "reset", "set_params", "load_world",
                                    "play"])
def test_a_viewer_cannot_change_the_world(operator: Client, viewer: Client,
                                          action: str) -> None:
    operator.spawn(spheres(["ball"], [[0.0, 0.0, 1.0]], radius=0.05))
    before = operator.status()
    params = operator.get_params()
    attempts = {
        "spawn": lambda: viewer.spawn(spheres(["intruder"], [[0.0, 0.0, 2.0]], radius=0.05)),
        "step": lambda: viewer.step(10),
        "reset": lambda: viewer.reset(),
        "set_params": lambda: viewer.set_params({"timestep": 0.01}),
        "load_world": lambda: viewer.load_world("pybullet"),
        "play": lambda: viewer.play(),
    }
    with pytest.raises(AccessDeniedError, match=f"refused this request at once.*'{action}'"):
        attempts[action]()
    after = operator.status()
    assert (after.step, after.entity_count, after.engine, after.state) == (
        before.step, before.entity_count, before.engine, before.state)
    assert [entity.name for entity in operator.list()] == ["ball"]
    assert operator.get_params() == params


def test_a_viewer_cannot_inject_telemetry(secured: EmbeddedDaemon, operator: Client) -> None:
    assert _forged_telemetry_reaches_operator(secured.endpoint, INSTANCE, BOB, ALICE) is False


def test_an_operator_cannot_inject_telemetry_either(secured: EmbeddedDaemon,
                                                   operator: Client) -> None:
    """Nobody but the daemon publishes on its keys: an operator's put is dropped too."""
    assert _forged_telemetry_reaches_operator(secured.endpoint, INSTANCE, ALICE, ALICE) is False


def test_without_users_the_same_injection_works(daemons: dict[str, EmbeddedDaemon]) -> None:
    """The injection test can see an injection: on an open daemon it arrives."""
    daemon = start_daemon(daemons, "mujoco")
    assert _forged_telemetry_reaches_operator(daemon.endpoint, daemon.instance, None, None)


def _forged_telemetry_reaches_operator(endpoint: str, instance: str,
                                       intruder: Credentials | None,
                                       listener: Credentials | None) -> bool:
    """Whether a sample the intruder puts on the telemetry key reaches a subscriber of
    another client. The intruder's liveliness round trip after its put means the daemon
    has handled it (one link keeps its order), so a copy it forwarded is already on its
    way to the listener, sub-millisecond on loopback: three more of the daemon's samples
    (at least 40 ms at 50 Hz) close the watch. On an open daemon the copy does arrive."""
    keys = Keys(instance)
    received: queue.SimpleQueue[bytes] = queue.SimpleQueue()
    listening = open_session(endpoint, credentials=listener)
    intruding = open_session(endpoint, credentials=intruder)
    try:
        subscriber = listening.declare_subscriber(
            keys.telemetry, lambda sample: received.put(sample.payload.to_bytes()))
        received.get(timeout=WAIT_S)  # the subscription is in place
        # Not a declared publisher: it sends only once told of a matching subscriber, which
        # access control never tells a client, so this test passed with `put` allowed
        # inbound. A session's put, with no publisher on the key, is sent regardless.
        assert daemon_alive(intruding, keys, WAIT_S)  # the session reaches the daemon
        intruding.put(keys.telemetry, FORGED)
        assert daemon_alive(intruding, keys, WAIT_S)  # ... and the put has arrived
        genuine = 0
        while genuine < 3:
            if received.get(timeout=WAIT_S) == FORGED:
                return True
            genuine += 1
        subscriber.undeclare()
        return False
    finally:
        close_session(intruding)
        close_session(listening)


def test_a_viewer_cannot_answer_for_the_daemon(secured: EmbeddedDaemon,
                                               operator: Client) -> None:
    """A rogue queryable on the daemon's control keys is never asked."""
    assert _rogue_answers(secured.endpoint, BOB, operator) == 0


def test_without_users_a_rogue_queryable_answers(daemons: dict[str, EmbeddedDaemon]) -> None:
    """The rogue test can see a rogue: on an open daemon it is asked."""
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=WAIT_S) as client:
        assert _rogue_answers(daemon.endpoint, None, client) > 0


def _rogue_answers(endpoint: str, intruder: Credentials | None, operator: Client) -> int:
    """How many of 20 status requests of ``operator`` a queryable that the intruder
    declares on the daemon's control keys answers (with the instance name "rogue")."""
    genuine = operator.status()
    asked = threading.Event()
    rogue = open_session(endpoint, credentials=intruder)
    try:
        def answer(query: zenoh.Query) -> None:
            asked.set()
            forged = {**asdict(genuine), "state": genuine.state.value, "instance": "rogue"}
            with query:
                query.reply(query.key_expr, encode_reply(Reply(ResultCode.OK, result=forged)))
        queryable = rogue.declare_queryable(operator.keys.control_all, answer)
        # A round trip to the daemon follows the declaration on the same link (the
        # intruder's own gets would reach its own queryable first: ask liveliness).
        assert daemon_alive(rogue, operator.keys, WAIT_S)
        answers = sum(operator.status().instance == "rogue" for _ in range(20))
        queryable.undeclare()
        return answers if answers else int(asked.is_set())
    finally:
        close_session(rogue)


# -- operator -----------------------------------------------------------------------------
def test_an_operator_can_do_everything(operator: Client) -> None:
    events: queue.SimpleQueue[dict[str, object]] = queue.SimpleQueue()
    with operator.on_event(events.put), operator.telemetry(timeout=WAIT_S) as stream:
        assert operator.spawn(spheres(["ball"], [[0.0, 0.0, 1.0]], radius=0.05)) == ["ball"]
        assert events.get(timeout=WAIT_S)
        operator.set_params({"timestep": 0.001})
        assert operator.step(5).step == 5
        assert operator.reset().step == 0
        assert next(stream).instance == INSTANCE
    assert operator.load_world("mujoco").entity_count == 0


def test_the_control_lease_holds_and_ends_with_its_holder_under_users(
        secured: EmbeddedDaemon, operator: Client, viewer: Client) -> None:
    """Access control lets the lease see its holder's liveliness token go."""
    with pytest.raises(AccessDeniedError):
        viewer.take_control()
    events: queue.SimpleQueue[dict[str, object]] = queue.SimpleQueue()
    holder = Client(INSTANCE, secured.endpoint, timeout=WAIT_S, credentials=ALICE)
    try:
        assert holder.take_control()
        with operator.on_event(events.put):
            with pytest.raises(ControlHeldError):
                operator.step(1)
            holder.close()
            while events.get(timeout=WAIT_S).get("change") != "lost":
                pass
        assert operator.step(1).step == 1
    finally:
        holder.close()


def test_credentials_never_show_their_password() -> None:
    for credentials in (ALICE, Credentials("bob", password_sha256="ab" * 32)):
        shown = f"{credentials!r} {credentials} {credentials.describe()}"
        assert "alice-secret-1" not in shown and "ab" * 32 not in shown
        assert str(credentials.wire_password) not in shown


# -- TLS ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def certificates(tmp_path_factory: pytest.TempPathFactory) -> Certificates:
    return make_certificates(tmp_path_factory.mktemp("certs"))


@pytest.fixture(scope="module")
def tls_daemon(certificates: Certificates,
               tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[EmbeddedDaemon, str]]:
    """A daemon with mutual TLS whose users are known by certificate name only."""
    folder = tmp_path_factory.mktemp("tls-users")
    users = folder / "users.toml"
    users.write_text('[users.alice]\nrole = "operator"\ntls_name = "alice.robot"\n'
                     '[users.bob]\nrole = "viewer"\ntls_name = "bob.view"\n')
    users.chmod(0o600)
    endpoint = f"tls/127.0.0.1:{free_loopback_port()}"
    certs = certificates
    args = ["--users", str(users), "--listen", endpoint, "--tls-cert", str(certs.daemon.cert),
            "--tls-key", str(certs.daemon.key), "--tls-ca", str(certs.ca)]
    with EmbeddedDaemon("mujoco", instance="tls", extra_args=args) as daemon:
        assert endpoint in daemon.output
        yield daemon, endpoint


def _tls_client(endpoint: str, ca: Path, cert: Path | None = None,
                key: Path | None = None) -> Client:
    return Client("tls", endpoint, timeout=WAIT_S,
                  credentials=Credentials(tls_ca=ca, tls_cert=cert, tls_key=key))


def test_roles_follow_the_certificate_name(tls_daemon: tuple[EmbeddedDaemon, str],
                                           certificates: Certificates) -> None:
    _, endpoint = tls_daemon
    certs = certificates
    with _tls_client(endpoint, certs.ca, certs.alice.cert, certs.alice.key) as alice, \
            _tls_client(endpoint, certs.ca, certs.bob.cert, certs.bob.key) as bob:
        alice.load_world("mujoco")
        assert alice.step(3).step == 3
        assert bob.status().step == 3
        with pytest.raises(AccessDeniedError):
            bob.step(1)
        assert alice.status().step == 3


@pytest.mark.parametrize("who", ["mallory", "no-certificate", "daemon-not-trusted"])
def test_tls_refuses_a_client_of_another_ca(tls_daemon: tuple[EmbeddedDaemon, str],
                                            certificates: Certificates, who: str) -> None:
    """mallory's certificate names alice but another CA signed it; a client with no
    certificate; a client that trusts another CA than the daemon's."""
    _, endpoint = tls_daemon
    certs = certificates
    credentials = {
        "mallory": Credentials(tls_ca=certs.ca, tls_cert=certs.mallory.cert,
                               tls_key=certs.mallory.key),
        "no-certificate": Credentials(tls_ca=certs.ca),
        "daemon-not-trusted": Credentials(tls_ca=certs.other_ca, tls_cert=certs.alice.cert,
                                          tls_key=certs.alice.key),
    }[who]
    with pytest.raises(AccessDeniedError, match="refused this session"):
        open_session(endpoint, credentials=credentials)


def test_plain_tcp_beside_tls_gives_a_stranger_nothing(
        tls_daemon: tuple[EmbeddedDaemon, str]) -> None:
    """Users known by certificate only: no password check, so a plain TCP session opens,
    but default deny hides even the daemon's token."""
    daemon, _ = tls_daemon
    session = open_session(daemon.endpoint)
    try:
        replies = list(session.liveliness().get(Keys("tls").alive, timeout=2.0))
        assert [r for r in replies if r.ok is not None] == []
        replies = list(session.get(Keys("tls").control("status"),
                                   payload=msgpack.packb({"v": 1, "op": "status"}),
                                   timeout=2.0))
        assert [r for r in replies if r.ok is not None] == []
    finally:
        close_session(session)


# -- the command line ---------------------------------------------------------------------
def _cli(daemon: EmbeddedDaemon, args: list[str],
         env: dict[str, str] | None = None) -> tuple[int, str]:
    result = CliRunner().invoke(cli_app, ["--connect", daemon.endpoint, "--instance", INSTANCE,
                                          *args], env=env)
    return result.exit_code, result.output


def test_the_cli_takes_a_password_file_and_the_environment(secured: EmbeddedDaemon,
                                                           tmp_path: Path) -> None:
    (tmp_path / "alice.pw").write_text("alice-secret-1\n")
    code, output = _cli(secured, ["--user", "alice", "--password-file",
                                  str(tmp_path / "alice.pw"), "status", "--json"])
    assert code == 0, output
    assert "alice-secret-1" not in output
    code, output = _cli(secured, ["pause"],
                        env={"GALTON_USER": "bob", "GALTON_PASSWORD": "bob-secret-2"})
    assert code == 1
    assert "access denied (client side): pause: daemon 'secured' is there" in output
    assert "bob-secret-2" not in output


def test_the_cli_says_access_denied_without_echoing_the_password(
        secured: EmbeddedDaemon) -> None:
    code, output = _cli(secured, ["status"],
                        env={"GALTON_USER": "alice", "GALTON_PASSWORD": "guess-1234"})
    assert code == 1
    assert "access denied (client side): a daemon listens at" in output
    assert "guess-1234" not in output and wire_password("alice", "guess-1234") not in output


def test_discovery_takes_credentials(secured: EmbeddedDaemon) -> None:
    """A viewer finds the daemon (status and capabilities are a viewer's); with no
    credentials the session itself is refused."""
    from galton.client import discover_at

    found = {d.instance: d for d in discover_at(secured.endpoint, 5.0, BOB)}
    assert found[INSTANCE].engine == "mujoco" and found[INSTANCE].host
    with pytest.raises(AccessDeniedError):
        discover_at(secured.endpoint, 5.0)


def test_the_password_dictionary_is_gone_once_the_daemon_serves(tmp_path: Path) -> None:
    """Zenoh reads the usrpwd dictionary when the session opens; the daemon removes it
    then, so a SIGKILL afterwards strands no file of password hashes."""
    import signal
    import tempfile

    def dictionaries() -> set[Path]:
        return set(Path(tempfile.gettempdir()).glob("galton-usrpwd-*"))

    before = dictionaries()
    daemon = EmbeddedDaemon("mujoco", instance="dictionary-gone",
                            extra_args=["--users", str(users_file(tmp_path))]).start()
    try:
        assert dictionaries() - before == set()
        assert daemon.process is not None
        daemon.process.send_signal(signal.SIGKILL)
        daemon.process.wait(30)
        assert dictionaries() - before == set()
    finally:
        daemon.stop()
