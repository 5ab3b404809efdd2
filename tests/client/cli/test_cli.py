"""The galton-client CLI through typer's runner, against real daemons: the clock, the
world's parameters, streams, discovery, errors and choices."""

from __future__ import annotations

import json

import pytest
from support.cli import NOWHERE, flat, invoke, run, target_of

from galton.client import Client, EmbeddedDaemon, wait_for_daemon
from galton.client.cli.common import package_version
from galton.protocol import BODY_SHAPES, RESET_SCOPES
from galton.protocol.operations import OPERATIONS


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return target_of(daemons["mujoco"])


def test_status_json(target: list[str]) -> None:
    status = invoke([*target, "status", "--json"])
    assert status["engine"] == "mujoco" and status["state"] == "stopped"


def test_manual_control_round(target: list[str]) -> None:
    spawned = invoke([*target, "spawn", "sphere", "b", "--count", "3", "--json"])
    assert spawned["names"] == ["b_0", "b_1", "b_2"]
    assert invoke([*target, "step", "25", "--json"])["step"] == 25
    assert invoke([*target, "play", "--rtf", "0", "--json"])["state"] == "playing"
    assert invoke([*target, "set-rtf", "2.5", "--json"])["target_rtf"] == 2.5
    assert invoke([*target, "pause", "--json"])["state"] == "paused"
    assert invoke([*target, "reset", "--scope", "time", "--json"])["step"] == 0
    assert invoke([*target, "stop", "--json"])["state"] == "stopped"
    assert invoke([*target, "reset", "--json"])["entity_count"] == 0


def test_step_and_run_until_read_states(target: list[str]) -> None:
    invoke([*target, "spawn", "plane", "ground", "--pos", "0,0,0", "--json"])
    invoke([*target, "spawn", "sphere", "a", "b", "--pos", "0,0,0.5,1,0,0.5", "--json"])
    stepped = invoke([*target, "step", "10", "--read", "b", "--json"])
    assert stepped["names"] == ["b"] and stepped["step"] == 10
    assert stepped["poses"][0][:2] == [1.0, 0.0] and stepped["twists"][0][2] < 0
    ran = invoke([*target, "run-until", "0.2", "--json"])
    assert ran["sim_time"] >= 0.2 and "names" not in ran
    rest = invoke([*target, "run-until", "20", "--read", "a,b", "--until-rest", "0.01,0.1",
                   "--json"])
    assert rest["at_rest"] is True and rest["sim_time"] < 20
    assert rest["names"] == ["a", "b"] and all(p[2] < 0.1 for p in rest["poses"])


def test_until_rest_needs_read_before_any_request(target: list[str]) -> None:
    result = run([*target, "run-until", "1", "--until-rest", "0.01,0.1"])
    assert result.exit_code == 2 and "--until-rest needs --read" in flat(result.output)
    assert invoke([*target, "status", "--json"])["step"] == 0


def test_params_show_and_set(target: list[str]) -> None:
    assert invoke([*target, "params", "timestep=0.001", "--json"])["timestep"] == 0.001
    assert invoke([*target, "params", "--json"])["timestep"] == 0.001
    gravity = invoke([*target, "params", "gravity=[0,0,-3]", "--json"])["gravity"]
    assert gravity == [0, 0, -3]
    shown = run([*target, "params"])
    assert shown.exit_code == 0, shown.output
    assert "(* : not the default)" in flat(shown.output)
    assert "0.001 *" in flat(shown.output) and "MuJoCo's default" in flat(shown.output)


def test_capabilities(target: list[str]) -> None:
    found = invoke([*target, "capabilities", "--json"])
    assert found["engine"] == "mujoco" and "sphere" in found["body_shapes"]
    assert "timestep" in found["params"]
    human = run([*target, "capabilities"])
    assert human.exit_code == 0 and "timestep" in human.output


def test_watch_prints_telemetry_lines(target: list[str]) -> None:
    result = run([*target, "watch", "--count", "2", "--json"])
    assert result.exit_code == 0, result.output
    lines = [json.loads(line) for line in result.stdout.splitlines()]
    assert len(lines) == 2 and lines[1]["seq"] > lines[0]["seq"]


def test_human_output_renders(target: list[str]) -> None:
    result = run([*target, "status"])
    assert result.exit_code == 0 and "mujoco" in result.output


def test_a_refusal_is_one_line_naming_the_wire_code(target: list[str]) -> None:
    invoke([*target, "spawn", "sphere", "ball", "--json"])
    result = run([*target, "delete", "bal"])
    assert result.exit_code == 1 and result.stdout == ""
    assert result.stderr.splitlines() == [
        "galton-client: NOT_FOUND (1): no entity named 'bal' (did you mean 'ball'?)"]
    taken = run([*target, "spawn", "sphere", "ball"])
    assert taken.exit_code == 1 and taken.stderr.startswith("galton-client: NAME_NOT_UNIQUE (6)")


def test_unreachable_daemon_says_client_side() -> None:
    result = run([*NOWHERE, "status"])
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert result.stderr.startswith("galton-client: unreachable (client side):")
    assert ".rs:" not in result.stderr and ".cargo" not in result.stderr  # Zenoh's source


def declared_choices(op: str, name: str) -> tuple[str, ...]:
    arg = OPERATIONS[op].arg(name)
    assert arg is not None and arg.choices
    return arg.choices


@pytest.mark.parametrize(("command", "choices"), [
    (["spawn", "cube", "a"], BODY_SHAPES),
    (["reset", "--scope", "everything"], RESET_SCOPES),
    (["load-world", "bullet"], declared_choices("load_world", "engine")),
    (["entities", "--kind", "moving"], declared_choices("list", "kind")),
    (["load-model", "--format", "sdf", "--path", "x.sdf"],
     declared_choices("load_model", "format")),
], ids=["shape", "scope", "engine", "kind", "format"])
def test_a_bad_choice_fails_before_any_round_trip(command: list[str],
                                                  choices: tuple[str, ...]) -> None:
    """Exit code 2 naming every valid choice, though no daemon could have been reached."""
    result = run([*NOWHERE, *command])
    assert result.exit_code == 2, result.output
    assert "is not one of " + ", ".join(repr(c) for c in choices) in flat(result.output)
    assert "unreachable" not in result.output


def test_a_good_choice_goes_on_to_the_daemon() -> None:
    """The same command line with a valid shape gets as far as the (missing) daemon."""
    result = run([*NOWHERE, "spawn", "sphere", "a"])
    assert result.exit_code == 1 and "unreachable (client side)" in result.stderr


def test_version() -> None:
    result = run(["--version"])
    assert result.exit_code == 0 and result.stdout == f"galton-client {package_version()}\n"
    assert package_version()[0].isdigit()


@pytest.mark.parametrize("command", ["daemons", "ls"])
def test_daemons_lists_one_per_engine(daemons: dict[str, EmbeddedDaemon], command: str) -> None:
    """Two daemons side by side, meshed, both found through one endpoint (ls: old name)."""
    first = EmbeddedDaemon("mujoco", instance="ls-mujoco").start()
    second = EmbeddedDaemon("pybullet", instance="ls-pybullet",
                            extra_args=["--connect", first.endpoint]).start()
    try:
        with Client(first.instance, first.endpoint) as probe:
            wait_for_daemon(probe.session, second.instance, 30)
        for connect in (first.endpoint, f"{first.endpoint},{second.endpoint}"):
            found = invoke(["--connect", connect, command, "--json"])
            engines = {d["instance"]: d["engine"] for d in found}
            assert engines["ls-mujoco"] == "mujoco" and engines["ls-pybullet"] == "pybullet"
            assert all({"instance", "engine", "state"} <= set(d) for d in found)
    finally:
        second.stop()
        first.stop()
