"""galton-client's worlds and snapshot commands through typer's runner, against a real
daemon: worlds, create-world, fork-world, delete-world, snapshot to a slot and a file,
restore from either, snapshots, delete-snapshot, predict, compare, and their refusals."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from support.cli import flat, invoke, run, target_of
from support.worlds import clean

from galton.client import Client, EmbeddedDaemon, plane, spheres


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> Iterator[list[str]]:
    with clean(mujoco_sim) as sim:
        sim.spawn(plane())
        sim.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05))
        yield target_of(daemons["mujoco"])


def test_worlds_create_fork_delete(target: list[str]) -> None:
    assert [w["name"] for w in invoke([*target, "worlds", "--json"])] == ["default"]
    made = invoke([*target, "create-world", "empty", "gravity=[0,0,-1]", "--engine",
                   "pybullet", "--json"])
    assert made[0]["engine"] == "pybullet" and not made[0]["live"]
    fork = invoke([*target, "fork-world", "copy", "--json"])
    assert fork[0]["entity_count"] == 2
    listed = invoke([*target, "list-worlds", "--json"])
    assert [w["name"] for w in listed] == ["default", "empty", "copy"]
    assert invoke([*target, "delete-world", "copy", "--json"]) == {"deleted": "copy"}
    human = run([*target, "worlds"])
    assert human.exit_code == 0 and "empty" in flat(human.output)


def test_snapshot_to_a_slot_and_a_file_then_restore(target: list[str],
                                                    tmp_path: Path) -> None:
    out = tmp_path / "world.snap"
    (taken,) = invoke([*target, "snapshot", "zero", "--out", str(out), "--json"])
    assert taken["slot"] == "zero" and taken["nbytes"] == out.stat().st_size
    invoke([*target, "step", "25", "--json"])
    (row,) = invoke([*target, "restore", "--file", str(out), "--json"])
    assert row["step"] == 0
    invoke([*target, "step", "5", "--json"])
    (row,) = invoke([*target, "restore", "--slot", "zero", "--json"])
    assert row["step"] == 0
    assert [s["slot"] for s in invoke([*target, "snapshots", "--json"])] == ["zero"]
    assert invoke([*target, "delete-snapshot", "zero", "--json"]) == {"deleted": "zero"}
    assert "no snapshot" in run([*target, "snapshots"]).output


def test_commands_act_on_a_side_world(target: list[str]) -> None:
    invoke([*target, "fork-world", "side", "--json"])
    (taken,) = invoke([*target, "snapshot", "s", "--world", "side", "--json"])
    assert taken["world"] == "side"
    found = invoke([*target, "predict", "0.01", "--every", "0.004", "--read", "ball",
                    "--world", "side", "--json"])
    assert found["names"] == ["ball"] and len(found["times"]) == len(found["poses"]) == 3
    human = run([*target, "predict", "0.01", "--read", "ball"])
    assert human.exit_code == 0 and "steps ahead" in flat(human.output)
    stepped = invoke([*target, "step", "7", "--world", "side", "--json"])
    live = invoke([*target, "status", "--json"])
    sides = {w["name"]: w["step"] for w in invoke([*target, "worlds", "--json"])}
    assert stepped["step"] == sides["side"] == 7 and live["step"] == sides["default"] == 0


def test_predict_many_futures_with_a_perturbation(target: list[str]) -> None:
    found = invoke([*target, "predict", "0.02", "--every", "0.01", "--read", "ball",
                    "--futures", "3", "--perturb", "position=0.001", "--seed", "4",
                    "--json"])
    assert (found["futures"], found["seed"]) == (3, 4)
    assert len(found["poses"]) == 3 and len(found["spread"]) == len(found["times"]) == 3
    assert found["spread"][-1][0] > 0
    human = run([*target, "predict", "0.02", "--read", "ball", "--futures", "2",
                 "--perturb", "position=0.001,velocity=0.01"])
    assert human.exit_code == 0 and "2 futures" in flat(human.output)
    bad = run([*target, "predict", "0.02", "--futures", "2", "--perturb", "size=1"])
    assert bad.exit_code != 0 and "position" in flat(bad.output)


def test_compare_prints_errors_and_score(target: list[str]) -> None:
    found = invoke([*target, "compare", "ball", "--poses", "0.03,0.04,0.5,0,0,0,1",
                    "--json"])
    assert found["position_errors"] == pytest.approx([0.05])
    assert found["score"] == pytest.approx(5.0)
    corrected = invoke([*target, "compare", "ball", "--poses", "0.03,0.04,0.5,0,0,0,1",
                        "--correct", "--json"])
    assert corrected["corrected"]
    again = run([*target, "compare", "ball", "--poses", "0.03,0.04,0.5,0,0,0,1"])
    assert again.exit_code == 0 and "anomaly score 0" in flat(again.output)


def test_compare_with_a_trigger_counts_the_streak(target: list[str]) -> None:
    """--trigger THRESHOLD:WINDOW: the daemon's streak, suggested once it is WINDOW long."""
    args = [*target, "compare", "ball", "--poses", "0.03,0.04,0.5", "--trigger", "3:2"]
    first, second = invoke([*args, "--json"]), invoke([*args, "--json"])
    assert (first["streak"], first["suggested"]) == (1, False)
    assert (second["streak"], second["suggested"]) == (2, True)
    human = run(args)
    assert human.exit_code == 0 and "in a row: 3" in flat(human.output)
    bad = run([*args[:-1], "3"])
    assert bad.exit_code != 0 and "THRESHOLD:WINDOW" in flat(bad.output)


def test_compare_with_a_trigger_that_calibrates_is_checked_first(target: list[str]) -> None:
    """--calibrate FIT (with --trigger): the fit is checked before the comparison counts;
    without --trigger it is refused on the command line."""
    args = [*target, "compare", "ball", "--poses", "0.03,0.04,0.5", "--trigger", "3:2"]
    unknown = run([*args, "--calibrate", "crate.friction"])
    assert unknown.exit_code != 0 and "crate" in flat(unknown.output)
    counted = invoke([*args, "--calibrate", "ball.friction", "--calibrate-bounds",
                      "ball.friction=0.1:1", "--calibrate-max-predictions", "10", "--json"])
    assert counted["streak"] == 1 and not counted["calibrating"]  # the refusal counted none
    lone = run([*target, "compare", "ball", "--poses", "0.03,0.04,0.5", "--calibrate",
                "ball.friction"])
    assert lone.exit_code == 2 and "--trigger" in flat(lone.output)


def test_compare_takes_positions_as_set_states_does(target: list[str]) -> None:
    """x,y,z alone is an unrotated pose, in compare as in set-states (issue 33)."""
    short = invoke([*target, "compare", "ball", "--poses", "0.03,0.04,0.5", "--json"])
    full = invoke([*target, "compare", "ball", "--poses", "0.03,0.04,0.5,0,0,0,1", "--json"])
    assert short["position_errors"] == full["position_errors"]
    assert short["angle_errors"] == full["angle_errors"] and short["score"] == full["score"]


@pytest.mark.parametrize("args", [["snapshot"], ["restore"],
                                  ["restore", "--slot", "a", "--file", "x"],
                                  ["compare", "ball", "--poses", "1,2"]])
def test_bad_command_lines_exit_2_before_any_request(target: list[str],
                                                     args: list[str]) -> None:
    assert run([*target, *args]).exit_code == 2


def test_refusals_are_one_line_naming_the_code(target: list[str]) -> None:
    result = run([*target, "restore", "--slot", "nothing"])
    assert result.exit_code == 1 and "NOT_FOUND" in result.output
    result = run([*target, "delete-world", "default"])
    assert result.exit_code == 1 and "INVALID_ARGUMENT" in result.output
