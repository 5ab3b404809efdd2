"""galton-client's joint and wrench commands through typer's runner, against a real daemon:
load-model's base and search path, joints, get-joints, set-joints, joint-targets, step and
run-until reading joints, wrench and clear-wrenches, call with joint values, and refusals."""

from __future__ import annotations

from pathlib import Path

import pybullet_data
import pytest
from support.cli import NOWHERE, flat, invoke, run, target_of

from galton.client import Client, EmbeddedDaemon
from galton.client.cli.common import console
from galton.protocol.operations import OPERATIONS

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
FREE_KUKA = KUKA.with_name("model_free_base.urdf")  # its base has a mass: it can float
JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return target_of(daemons["mujoco"])


@pytest.fixture
def kuka(target: list[str]) -> list[str]:
    """The target, with the iiwa loaded from this machine's file (meshes beside it)."""
    invoke([*target, "load-model", "--file", str(KUKA), "--search-path", str(KUKA.parent),
            "--fixed-base", "--json"])
    return target


def test_a_prefix_names_a_model_as_the_ros2_front_does(target: list[str]) -> None:
    """--prefix arm names the links arm/<link> (issue 47: it gave armlbr_iiwa_link_0)."""
    loaded = invoke([*target, "load-model", "--file", str(KUKA), "--search-path",
                     str(KUKA.parent), "--prefix", "arm", "--json"])
    assert loaded["names"][:2] == ["arm/lbr_iiwa_link_0", "arm/lbr_iiwa_link_1"]
    joints = invoke([*target, "joints", "--json"])
    assert "arm/lbr_iiwa_joint_1" in [j["name"] for j in joints]


def test_load_model_bases_and_the_joint_table(target: list[str],
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    loaded = invoke([*target, "load-model", "--file", str(FREE_KUKA), "--search-path",
                     str(KUKA.parent), "--floating-base", "--prefix", "f_", "--json"])
    assert loaded["names"][0] == "f_lbr_iiwa_link_0" and len(loaded["names"]) == 8
    joints = invoke([*target, "joints", "--json"])
    assert [j["name"] for j in joints] == ["f_lbr_iiwa_link_0:free", *(f"f_{n}" for n in JOINTS)]
    assert joints[0]["type"] == "free" and joints[1]["axis"] == [0.0, 0.0, 1.0]
    monkeypatch.setattr(console, "width", 80)  # issue 33: names cut to "lbr_iiwa_j…"
    printed = run([*target, "joints", "--model", "f_lbr_iiwa_link_0"]).stdout
    assert "…" not in printed and all(len(line) <= 80 for line in printed.splitlines())
    assert all(f"f_{n}" in printed.split() for n in JOINTS)  # each whole, on one line
    table = flat(printed)
    assert "revolute" in table and "(world)" in table
    one = invoke([*target, "joints", "f_lbr_iiwa_joint_2", "--json"])
    assert [j["name"] for j in one] == ["f_lbr_iiwa_joint_2"]


def test_set_and_get_joints(kuka: list[str]) -> None:
    done = invoke([*kuka, "set-joints", *JOINTS[:2], "--positions", "0.5,-0.25",
                   "--velocities", "0.1", "--json"])
    assert done["names"] == JOINTS[:2] and done["step"] == 0
    states = invoke([*kuka, "get-joints", *JOINTS[:3], "--json"])
    assert states["names"] == JOINTS[:3]
    assert states["positions"] == pytest.approx([0.5, -0.25, 0.0])
    assert states["velocities"] == pytest.approx([0.1, 0.1, 0.0])
    assert len(invoke([*kuka, "get-joints", "--json"])["names"]) == 7
    table = flat(run([*kuka, "get-joints", JOINTS[0]]).stdout)
    assert f"{JOINTS[0]} 0.5 0.1 0" in table


def test_joint_targets_then_a_step_reading_joints(kuka: list[str]) -> None:
    invoke([*kuka, "params", "timestep=0.001", "--json"])
    held = invoke([*kuka, "joint-targets", "position", *JOINTS[:4], "--targets",
                   "0.2,0.3,0,-0.5", "--kp", "2000,2000,1000,1000", "--kd", "100,100,50,50",
                   "--max-effort", "300", "--json"])
    assert held["mode"] == "position" and held["names"] == JOINTS[:4]
    modes = {j["name"]: j["mode"] for j in invoke([*kuka, "joints", "--json"])}
    assert [modes[n] for n in JOINTS] == ["position"] * 4 + ["none"] * 3
    joints = invoke([*kuka, "step", "1000", "--read-joints", ",".join(JOINTS[:2]), "--json"])
    assert joints["step"] == 1000 and joints["positions"] == pytest.approx([0.2, 0.3], abs=0.05)
    both = invoke([*kuka, "step", "--read", "lbr_iiwa_link_7", "--read-joints", JOINTS[0],
                   "--json"])
    assert both["names"] == ["lbr_iiwa_link_7"] and both["joints"]["names"] == [JOINTS[0]]
    later = invoke([*kuka, "run-until", "1.5", "--read-joints", JOINTS[3], "--json"])
    assert later["sim_time"] >= 1.5 and later["positions"] == pytest.approx([-0.5], abs=0.05)
    invoke([*kuka, "joint-targets", "none", *JOINTS[:4], "--json"])
    assert {j["mode"] for j in invoke([*kuka, "joints", "--json"])} == {"none"}


def test_wrench_and_clear_wrenches(target: list[str]) -> None:
    invoke([*target, "params", "gravity=[0,0,0]", "--json"])
    invoke([*target, "spawn", "sphere", "a", "b", "--mass", "2", "--json"])
    invoke([*target, "wrench", "a", "b", "--force", "4,0,0", "--at", "0,0,1,0.2,0,1",
            "--json"])
    twists = invoke([*target, "step", "10", "--read", "a,b", "--json"])["twists"]
    assert twists[0][0] > 0 and twists[1][0] > 0
    cleared = flat(run([*target, "clear-wrenches"]).stdout)
    assert cleared.startswith("cleared every wrench at step 10")
    invoke([*target, "wrench", "a", "--torque", "0,0,0.1", "--duration", "0.01", "--json"])
    assert invoke([*target, "clear-wrenches", "a", "--json"])["names"] == ["a"]


def test_call_packs_joint_values(kuka: list[str]) -> None:
    invoke([*kuka, "call", "set_joint_states",
            f'{{"names": ["{JOINTS[0]}", "{JOINTS[1]}"], "positions": [0.1, 0.2]}}'])
    result = invoke([*kuka, "call", "get_joint_states", f'{{"names": ["{JOINTS[1]}"]}}'])
    assert result["positions"] == pytest.approx([0.2]) and result["efforts"] == [0.0]


def test_refusals_name_their_wire_code(kuka: list[str]) -> None:
    unknown = run([*kuka, "get-joints", "lbr_iiwa_joint_l"])
    assert unknown.exit_code == 1 and unknown.stderr.startswith("galton-client: NOT_FOUND (1)")
    assert "did you mean" in unknown.stderr
    nan = run([*kuka, "joint-targets", "position", JOINTS[0], "--targets", "0.1", "--kp", "nan"])
    assert nan.exit_code == 1 and "INVALID_ARGUMENT" in nan.stderr
    fixed_base = run([*kuka, "wrench", "lbr_iiwa_link_0", "--force", "1,0,0"])
    assert fixed_base.exit_code == 1 and "INVALID_ARGUMENT" in fixed_base.stderr


@pytest.mark.parametrize("command", [
    ["joint-targets", "stiff", "j"],
    ["set-joints", "a", "b", "--positions", "1,2,3"],
    ["wrench", "a", "--force", "1,2"],
    ["run-until", "1", "--read", "a", "--read-joints", "j"],
], ids=["mode", "count", "width", "run-until-both"])
def test_bad_command_lines_exit_2_before_any_round_trip(command: list[str]) -> None:
    result = run([*NOWHERE, *command])
    assert result.exit_code == 2, result.output


def test_the_modes_offered_are_the_protocols() -> None:
    declared = OPERATIONS["set_joint_targets"].arg("mode")
    assert declared is not None and declared.choices
    refused = run([*NOWHERE, "joint-targets", "stiff", "j"])
    assert refused.exit_code == 2
    assert all(f"'{mode}'" in refused.output for mode in declared.choices), refused.output


def test_operation_names_answer_as_hidden_aliases() -> None:
    for alias in ("get-joint-states", "set-joint-states", "set-joint-targets", "apply-wrench"):
        assert run([alias, "--help"]).exit_code == 0
        assert alias not in run(["--help"]).stdout
