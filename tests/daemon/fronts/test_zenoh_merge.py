"""``--zenoh-config FILE`` merged predictably (daemon/fronts/zenoh_config.py): what the command line
gives wins, else the file, else the daemon's defaults; and the daemon's command line
refuses bad security options with one line."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest
import zenoh
from typer.testing import CliRunner

from galton.client.sdk.embedded import free_loopback_port
from galton.client.transport.session import close_session, open_session
from galton.daemon.cli import app as daemon_app
from galton.daemon.fronts.zenoh_config import (
    DEFAULT_LISTEN,
    DEFAULT_TLS_LISTEN,
    LISTEN,
    MODE,
    MULTICAST,
    file_says,
    listen_endpoints,
    merge,
)
from galton.daemon.server import DaemonOptions, zenoh_config
from galton.protocol.errors import InvalidArgumentError

NOTHING: dict[str, Any] = {}


def said(text: str) -> dict[str, Any]:
    return file_says(zenoh.Config.from_json5(text))


def test_an_empty_file_says_nothing_and_gets_the_daemons_defaults() -> None:
    silent = said("{}")
    assert all(value is None for value in silent.values())
    assert merge(silent, [], [], False, NOTHING) == {
        MODE: "peer", MULTICAST: False, LISTEN: [DEFAULT_LISTEN]}


def test_the_files_endpoints_mode_and_scouting_are_honoured() -> None:
    text = ('{mode: "peer", listen: {endpoints: ["tcp/127.0.0.1:9001"]}, '
            'scouting: {multicast: {enabled: true}}}')
    assert merge(said(text), [], [], False, NOTHING) == {}


def test_the_files_false_multicast_and_client_mode_are_honoured() -> None:
    text = '{mode: "client", scouting: {multicast: {enabled: false}}}'
    assert merge(said(text), [], [], False, NOTHING) == {LISTEN: [DEFAULT_LISTEN]}


def test_the_command_line_wins_over_the_file() -> None:
    text = '{listen: {endpoints: ["tcp/127.0.0.1:9001"]}, scouting: {multicast: {enabled: false}}}'
    inserts = merge(said(text), ["tcp/127.0.0.1:9002"], ["tcp/10.0.0.2:7447"], True, NOTHING)
    assert inserts[LISTEN] == ["tcp/127.0.0.1:9002"]
    assert inserts["connect/endpoints"] == ["tcp/10.0.0.2:7447"]
    assert inserts[MULTICAST] is True


def test_tls_options_add_a_tls_endpoint_unless_one_is_named() -> None:
    tls = {"transport/link/tls/listen_certificate": "/x.pem"}
    assert merge(said("{}"), [], [], False, tls)[LISTEN] == [DEFAULT_LISTEN, DEFAULT_TLS_LISTEN]
    named = ["tcp/127.0.0.1:9002", "tls/127.0.0.1:9003"]
    assert merge(said("{}"), named, [], False, tls)[LISTEN] == named


@pytest.mark.parametrize(("text", "security"), [
    ('{access_control: {enabled: true}}', {"access_control": {"enabled": True}}),
    ('{transport: {auth: {usrpwd: {dictionary_file: "/d.txt"}}}}',
     {"transport/auth/usrpwd/dictionary_file": "/e.txt"}),
])
def test_users_and_a_file_with_its_own_access_rules_are_refused(
        text: str, security: dict[str, Any]) -> None:
    with pytest.raises(InvalidArgumentError, match="both"):
        merge(said(text), [], [], False, security)


def test_a_daemon_config_listens_where_the_file_says(tmp_path: Path) -> None:
    """A real Zenoh peer opened from the merged configuration, reached at the file's
    endpoint (the file's endpoints used to be overridden)."""
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    path = tmp_path / "zenoh.json5"
    path.write_text(json.dumps({"listen": {"endpoints": [endpoint]}}))
    options = DaemonOptions(zenoh_config=path)
    config = zenoh_config(options)
    assert listen_endpoints(config) == [endpoint]  # what the ready line says
    assert json.loads(config.get_json(MULTICAST)) is False
    peer = zenoh.open(config)
    try:
        close_session(open_session(endpoint))
    finally:
        close_session(peer)


# -- the daemon's command line ------------------------------------------------------------
@pytest.mark.parametrize(("args", "expected"), [
    (["--users", "{missing}"], "cannot read the users file"),
    (["--users", "{bad}"], "user 'carol': role 'boss' is not one of operator, viewer"),
    (["--tls-ca", "{bad}"], "--tls-ca needs --tls-cert and --tls-key"),
    (["--tls-cert", "{bad}"], "--tls-cert and --tls-key go together"),
    (["--users", "{newline}"], "user name 'alice\\n' is not valid"),
])
def test_the_daemon_refuses_bad_security_options_in_one_line(
        tmp_path: Path, args: list[str], expected: str) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('[users.carol]\nrole = "boss"\npassword = "hunter2"\n')
    newline = tmp_path / "newline.toml"  # once split Zenoh's dictionary line: Zenoh's error
    newline.write_text('[users."alice\\n"]\nrole = "viewer"\npassword = "hunter2"\n')
    paths = {"missing": str(tmp_path / "missing.toml"), "bad": str(bad),
             "newline": str(newline)}
    result = CliRunner().invoke(daemon_app, [arg.format(**paths) for arg in args])
    assert result.exit_code == 2, result.output
    assert expected in result.output and "hunter2" not in result.output
