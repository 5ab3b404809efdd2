"""Client credentials (client/transport/credentials.py): where they come from, what reaches Zenoh,
and that a password is never echoed; ``galton-client hash-password``."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.cli import run
from typer.testing import CliRunner

from galton.client import Credentials
from galton.client.cli.app import app
from galton.client.transport.credentials import resolve_credentials
from galton.protocol.auth import wire_password
from galton.protocol.errors import InvalidArgumentError

SECRET = "s3cret-Passw0rd"


def test_the_wire_password_is_the_salted_hash() -> None:
    credentials = Credentials("alice", SECRET)
    assert credentials.wire_password == wire_password("alice", SECRET)
    settings = credentials.zenoh_settings()
    assert settings == {"transport/auth/usrpwd/user": "alice",
                        "transport/auth/usrpwd/password": wire_password("alice", SECRET)}
    hashed = Credentials("alice", password_sha256=wire_password("alice", SECRET).upper())
    assert hashed.wire_password == credentials.wire_password


@pytest.mark.parametrize(("fields", "expected"), [
    ({"password": SECRET}, "a password was given without a user"),
    ({"user": "alice"}, "user 'alice' was given without a password"),
    ({"user": "alice", "password": ""}, "the password of user 'alice' is empty"),
    ({"user": "al:ice", "password": SECRET}, "user name 'al:ice' is not valid"),
    ({"user": "alice", "password": SECRET, "password_sha256": "a" * 64}, "not both"),
    ({"user": "alice", "password_sha256": SECRET}, "must be 64 hex digits"),
    ({"user": "alice\n", "password": SECRET}, r"user name 'alice\\n' is not valid"),
    ({"user": "alice", "password_sha256": "a" * 64 + "\n"}, "must be 64 hex digits"),
    ({"tls_cert": Path("/nowhere.pem")}, "go together"),
    ({"tls_ca": Path("/nowhere.pem")}, "tls_ca '/nowhere.pem' is not a readable file"),
])
def test_bad_credentials_are_refused_without_their_password(
        fields: dict[str, object], expected: str) -> None:
    with pytest.raises(InvalidArgumentError, match=expected) as caught:
        Credentials(**fields)  # type: ignore[arg-type]
    assert SECRET not in str(caught.value)


@pytest.mark.parametrize("field", ["tls_ca", "tls_cert", "tls_key"])
def test_a_tls_file_that_is_not_pem_is_refused(tmp_path: Path, field: str) -> None:
    """Zenoh takes PEM only, and a file it cannot parse made ``zenoh.open`` fail like a
    refused handshake: the SDK said the daemon refused the session."""
    pem = tmp_path / "good.pem"
    pem.write_text("-----BEGIN CERTIFICATE-----\nMIIB\n-----END CERTIFICATE-----\n")
    (tmp_path / "cert.der").write_bytes(bytes([0x30, 0x82, 0x01, 0x0A]))
    files = {"tls_ca": pem, "tls_cert": pem, "tls_key": pem, field: tmp_path / "cert.der"}
    with pytest.raises(InvalidArgumentError, match=f"{field} '.*cert.der' is not a PEM file"):
        Credentials(**files)


def test_later_sources_win_field_by_field(tmp_path: Path) -> None:
    (tmp_path / "pw").write_text("from-file\n")
    (tmp_path / "ca.pem").write_text("-----BEGIN CERTIFICATE-----\nnot read here\n")
    (tmp_path / "creds.toml").write_text(
        'user = "alice"\npassword_file = "pw"\ntls_ca = "ca.pem"\n')
    environ = {"GALTON_CREDENTIALS": str(tmp_path / "creds.toml")}
    from_file = resolve_credentials(environ=environ)
    assert from_file == Credentials("alice", "from-file", tls_ca=tmp_path / "ca.pem")
    environ |= {"GALTON_USER": "bob", "GALTON_PASSWORD": "from-env"}
    assert resolve_credentials(environ=environ) == Credentials(
        "bob", "from-env", tls_ca=tmp_path / "ca.pem")
    (tmp_path / "option").write_text("from-option")
    assert resolve_credentials("carol", tmp_path / "option", environ=environ) == Credentials(
        "carol", "from-option", tls_ca=tmp_path / "ca.pem")
    assert resolve_credentials(environ={}) is None
    assert Credentials.from_env({"GALTON_USER": "dave", "GALTON_PASSWORD": "x"}) == (
        Credentials("dave", "x"))


@pytest.mark.parametrize(("text", "expected"), [
    ('user = "alice"\npasword = "x"\n', r"unknown field 'pasword'.*'password'"),
    ("user = 3\n", "user must be a string"),
    ("user = \n", "is not TOML"),
])
def test_a_bad_credentials_file_is_refused(tmp_path: Path, text: str, expected: str) -> None:
    (tmp_path / "creds.toml").write_text(text)
    with pytest.raises(InvalidArgumentError, match=expected):
        Credentials.from_file(tmp_path / "creds.toml")


def test_hash_password_prints_the_users_file_line() -> None:
    """From a pipe (no terminal), the password is its first line; nothing else is printed."""
    result = CliRunner().invoke(app, ["hash-password", "alice"], input=SECRET + "\n")
    assert result.exit_code == 0, result.output
    assert result.stdout.strip() == f'password_sha256 = "{wire_password("alice", SECRET)}"'


def test_hash_password_refuses_an_empty_input() -> None:
    result = CliRunner().invoke(app, ["hash-password", "alice"], input="")
    assert result.exit_code == 1
    assert "no password on standard input" in result.output


def test_a_bad_credential_option_is_a_bad_command_line(tmp_path: Path) -> None:
    result = run(["--user", "alice", "status"])
    assert result.exit_code == 2
    assert "user 'alice' was given without a password" in result.output
