"""galton-client take-control and release-control through typer's runner, against a real
daemon: a command holds control while it runs, and a command refused by another client's
control exits 1 with one line naming CONTROL_HELD and the holder."""

from __future__ import annotations

import pytest
from support.cli import flat, invoke, run, target_of

from galton.client import Client, EmbeddedDaemon


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return target_of(daemons["mujoco"])


def test_take_control_holds_it_while_the_command_runs(target: list[str],
                                                      mujoco_sim: Client) -> None:
    taken = invoke([*target, "take-control", "--hold", "0", "--json"])
    assert taken["instance"] == mujoco_sim.instance and taken["controller"]
    assert mujoco_sim.status().controller is None  # released when the command ended
    said = run([*target, "take-control", "--hold", "0"])
    assert said.exit_code == 0, said.output
    assert "holding control of" in said.stdout and "released control" in said.stdout


def test_release_control_with_nobody_holding_it_is_nothing_to_do(target: list[str]) -> None:
    assert invoke([*target, "release-control", "--json"]) == {"released": False}
    result = run([*target, "release-control"])
    assert result.exit_code == 0 and "nobody held control" in result.stdout


def test_commands_are_refused_while_another_client_holds_control(target: list[str],
                                                                 mujoco_sim: Client) -> None:
    with mujoco_sim.control():
        for command in (["step", "1"], ["release-control"], ["take-control", "--hold", "0"]):
            result = run([*target, *command])
            assert result.exit_code == 1, result.output
            assert "CONTROL_HELD (12)" in result.stderr and mujoco_sim.client_id in result.stderr
        status = invoke([*target, "status", "--json"])
        assert status["controller"] == mujoco_sim.client_id and status["step"] == 0


@pytest.mark.parametrize("hold", ["inf", "1e300", "nan"])
def test_a_hold_that_is_no_number_of_seconds_is_a_usage_error(target: list[str],
                                                              mujoco_sim: Client,
                                                              hold: str) -> None:
    """An endless or undefined --hold is refused before control is taken (leaving it out
    holds until Ctrl-C), not a traceback after."""
    result = run([*target, "take-control", "--hold", hold])
    assert result.exit_code == 2, (result.output, result.exception)
    assert "Invalid value for '--hold'" in flat(result.output)
    assert mujoco_sim.status().controller is None
