"""The galton-client CLI through typer's runner, against real daemons."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from galton.client import Client, EmbeddedDaemon, wait_for_daemon
from galton.client.cli import app

runner = CliRunner()


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    daemon = daemons["mujoco"]
    return ["--connect", daemon.endpoint, "--instance", daemon.instance]


def invoke(args: list[str]) -> dict | list:
    result = runner.invoke(app, args)
    assert result.exit_code == 0, result.output
    return json.loads(result.output)


def test_status_json(target: list[str]) -> None:
    status = invoke([*target, "status", "--json"])
    assert status["engine"] == "mujoco" and status["state"] == "stopped"


def test_manual_control_round(target: list[str]) -> None:
    spawned = invoke([*target, "spawn", "sphere", "--name", "b", "--count", "3", "--json"])
    assert spawned["names"] == ["b_0", "b_1", "b_2"]
    assert invoke([*target, "step", "25", "--json"])["step"] == 25
    assert invoke([*target, "play", "--rtf", "0", "--json"])["state"] == "playing"
    assert invoke([*target, "pause", "--json"])["state"] == "paused"
    assert invoke([*target, "reset", "--scope", "time", "--json"])["step"] == 0
    assert invoke([*target, "stop", "--json"])["state"] == "stopped"
    assert invoke([*target, "reset", "--json"])["entity_count"] == 0


def test_params_show_and_set(target: list[str]) -> None:
    assert invoke([*target, "params", "timestep=0.001", "--json"])["timestep"] == 0.001
    assert invoke([*target, "params", "--json"])["timestep"] == 0.001


def test_watch_prints_telemetry_lines(target: list[str]) -> None:
    result = runner.invoke(app, [*target, "watch", "--count", "2", "--json"])
    assert result.exit_code == 0, result.output
    lines = [json.loads(line) for line in result.output.splitlines()]
    assert len(lines) == 2 and lines[1]["seq"] > lines[0]["seq"]


def test_human_output_renders(target: list[str]) -> None:
    result = runner.invoke(app, [*target, "status"])
    assert result.exit_code == 0 and "mujoco" in result.output


def test_errors_are_one_line_and_exit_one(target: list[str]) -> None:
    result = runner.invoke(app, [*target, "reset", "--scope", "everything"])
    assert result.exit_code == 1
    assert "InvalidArgumentError" in result.output and "Traceback" not in result.output


def test_unreachable_daemon(target: list[str]) -> None:
    result = runner.invoke(app, ["--connect", "tcp/127.0.0.1:1", "status"])
    assert result.exit_code == 1 and "DaemonUnreachableError" in result.output


def test_ls_lists_a_daemon_per_engine(daemons: dict[str, EmbeddedDaemon]) -> None:
    """Two daemons side by side, meshed, both found through one endpoint."""
    first = EmbeddedDaemon("mujoco", instance="ls-mujoco").start()
    second = EmbeddedDaemon("pybullet", instance="ls-pybullet",
                            extra_args=["--connect", first.endpoint]).start()
    try:
        with Client(first.instance, first.endpoint) as probe:
            wait_for_daemon(probe.session, second.instance, 30)
        for connect in (first.endpoint, f"{first.endpoint},{second.endpoint}"):
            found = invoke(["--connect", connect, "ls", "--json"])
            engines = {d["instance"]: d["engine"] for d in found}
            assert engines["ls-mujoco"] == "mujoco" and engines["ls-pybullet"] == "pybullet"
            assert all({"instance", "engine", "state"} <= set(d) for d in found)
    finally:
        second.stop()
        first.stop()
