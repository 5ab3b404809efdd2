"""galton-client's scene commands against a real daemon: spawn, entities, get-states,
set-states, update, delete, load-model and load-world."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from support.cli import flat, invoke, run, target_of

from galton.client import Client, EmbeddedDaemon

MODEL = """<mujoco><worldbody>
  <body name="crate" pos="0 0 1"><freejoint/><geom type="box" size="0.1 0.1 0.1"/></body>
</worldbody></mujoco>"""


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return target_of(daemons["mujoco"])


def test_spawn_options_reach_the_world(target: list[str]) -> None:
    spawned = invoke([*target, "spawn", "box", "crate", "--count", "2", "--size", "0.1,0.2,0.3",
                      "--pos", "1,2,3", "--spacing", "0.5", "--mass", "2", "--friction", "0.7",
                      "--restitution", "0.1", "--rgba", "1,0,0,1", "--tags", "cargo,red",
                      "--json"])
    assert spawned["names"] == ["crate_0", "crate_1"]
    found = invoke([*target, "entities", "--json"])
    assert [e["size"] for e in found] == [[0.1, 0.2, 0.3]] * 2
    assert {(e["mass"], e["friction"], e["restitution"], tuple(e["tags"])) for e in found} == {
        (2.0, 0.7, 0.1, ("cargo", "red"))}
    states = invoke([*target, "get-states", "--json"])
    assert [p[:3] for p in states["poses"]] == [[1.0, 2.0, 3.0], [1.5, 2.0, 3.0]]
    shapes = invoke([*target, "get-shapes", "crate_1", "--json"])
    assert shapes == {"crate_1": [{"kind": "box", "size": [0.1, 0.2, 0.3],
                                   "pose": [0, 0, 0, 0, 0, 0, 1], "triangles": None}]}
    assert "box" in run([*target, "get-shapes"]).output
    # The table says what --size was: half sizes (issue 47: "size (m)" read as full ones).
    table = run([*target, "entities"]).output
    assert "half sizes (m)" in table and "0.1, 0.2, 0.3" in table


def test_spawn_a_mesh_from_an_obj_file_and_a_box_mesh_with_an_inertia(
        target: list[str], tmp_path: Path) -> None:
    obj = tmp_path / "pyramid.obj"
    obj.write_text("v -0.1 -0.1 -0.1\nv 0.1 -0.1 -0.1\nv 0.1 0.1 -0.1\nv -0.1 0.1 -0.1\n"
                   "v 0 0 0.2\nf 1 3 2\nf 1 4 3\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4/1 1/1 5/1\n")
    invoke([*target, "spawn", "mesh", "pyramid", "--mesh", str(obj), "--static", "--json"])
    invoke([*target, "spawn", "mesh", "crate", "--size", "0.1,0.2,0.3", "--inertia",
            "0.1,0.1,0.1", "--json"])
    found = {e["name"]: e for e in invoke([*target, "entities", "--json"])}
    assert found["pyramid"]["shape"] == "mesh" and found["pyramid"]["size"] == [0.1, 0.1, 0.2]
    assert found["crate"]["size"] == [0.1, 0.2, 0.3]
    [pyramid] = invoke([*target, "get-shapes", "pyramid", "--json"])["pyramid"]
    assert pyramid["triangles"] == [5, 6]  # the file's, not a box's
    assert "vertices" in run([*target, "get-shapes", "pyramid"]).output
    obj.write_text("v 0 0 0\nf 1 2 3\n")
    result = run([*target, "spawn", "mesh", "bad", "--mesh", str(obj)])
    assert result.exit_code != 0 and "line 2" in result.output
    assert "bad" not in {e["name"] for e in invoke([*target, "entities", "--json"])}


def test_spawn_with_twists_and_a_static_plane(target: list[str]) -> None:
    invoke([*target, "spawn", "plane", "ground", "--pos", "0,0,0", "--json"])
    invoke([*target, "spawn", "sphere", "a", "b", "--pos", "0,0,1,1,0,1",
            "--twists", "1,0,0,0,0,0", "--json"])
    states = invoke([*target, "get-states", "a", "b", "--json"])
    assert [t[0] for t in states["twists"]] == [1.0, 1.0]
    static = invoke([*target, "entities", "--kind", "static", "--json"])
    assert [e["name"] for e in static] == ["ground"]


def test_a_plane_is_the_ground_at_z_0_and_a_body_rests_on_it(target: list[str]) -> None:
    """One default everywhere: the CLI's plane is at z = 0, as the SDK's plane(); a box
    spawned at z = 0.5 (issue 33: it flew to 390 m from inside a plane at z = 1) falls onto
    it and rests."""
    invoke([*target, "spawn", "plane", "ground", "--json"])
    invoke([*target, "spawn", "box", "crate", "--size", "0.1,0.1,0.1", "--pos", "0,0,0.5",
            "--json"])
    assert invoke([*target, "get-states", "ground", "--json"])["poses"][0][:3] == [0, 0, 0]
    invoke([*target, "step", "2000", "--json"])
    z = invoke([*target, "get-states", "crate", "--json"])["poses"][0][2]
    assert z == pytest.approx(0.1, abs=0.01)  # its half height above the ground


def test_a_spawn_line_with_the_wrong_count_of_numbers_sends_nothing(target: list[str]) -> None:
    result = run([*target, "spawn", "sphere", "a", "b", "--pos", "0,0,1,2"])
    assert result.exit_code == 2 and "--pos needs 3 numbers per body" in flat(result.output)
    assert invoke([*target, "entities", "--json"]) == []


def test_entities_filters(target: list[str]) -> None:
    invoke([*target, "spawn", "sphere", "red_1", "red_2", "--tags", "red", "--json"])
    invoke([*target, "spawn", "sphere", "blue_1", "--pos", "0,1,1", "--json"])
    assert [e["name"] for e in invoke([*target, "entities", "--name", "red_*", "--json"])] == [
        "red_1", "red_2"]
    assert [e["name"] for e in invoke([*target, "entities", "--tag", "red", "--json"])] == [
        "red_1", "red_2"]
    assert invoke([*target, "entities", "--kind", "static", "--json"]) == []
    human = run([*target, "entities"])
    assert human.exit_code == 0 and "blue_1" in human.output


def test_set_states_then_get_states(target: list[str]) -> None:
    invoke([*target, "spawn", "sphere", "a", "b", "--json"])
    invoke([*target, "set-states", "a", "b", "--poses", "1,1,1,0,0,0,1,2,2,2,0,0,1,0",
            "--json"])
    invoke([*target, "set-states", "b", "--twists", "0,0,0,0,0,3", "--json"])
    states = invoke([*target, "get-states", "a", "b", "--json"])
    assert states["names"] == ["a", "b"]
    assert states["poses"] == [[1, 1, 1, 0, 0, 0, 1], [2, 2, 2, 0, 0, 1, 0]]
    assert states["twists"][1] == [0, 0, 0, 0, 0, 3]
    invoke([*target, "set-states", "a", "--poses", "5,5,5", "--json"])
    assert invoke([*target, "get-states", "a", "--json"])["poses"] == [[5, 5, 5, 0, 0, 0, 1]]
    table = run([*target, "get-states"])
    assert table.exit_code == 0 and "sim time" in table.output


def test_set_states_needs_something_to_set(target: list[str]) -> None:
    result = run([*target, "set-states", "a"])
    assert result.exit_code == 2 and "give --poses and/or --twists" in flat(result.output)


def test_update_and_delete(target: list[str]) -> None:
    invoke([*target, "spawn", "sphere", "a", "b", "c", "--json"])
    stamp = invoke([*target, "update", "a", "b", "--mass", "3", "--tags", "heavy", "--json"])
    assert stamp["names"] == ["a", "b"] and stamp["step"] == 0
    heavy = invoke([*target, "entities", "--tag", "heavy", "--json"])
    assert [(e["name"], e["mass"]) for e in heavy] == [("a", 3.0), ("b", 3.0)]
    invoke([*target, "delete", "a", "c", "--json"])
    assert [e["name"] for e in invoke([*target, "entities", "--json"])] == ["b"]
    refused = run([*target, "update", "b", "--restitution", "2"])
    assert refused.exit_code == 1 and "INVALID_ARGUMENT (5)" in refused.stderr


def test_load_model_from_a_local_file_or_the_daemons_path(target: list[str],
                                                           tmp_path: Path) -> None:
    model = tmp_path / "crate.xml"
    model.write_text(MODEL)
    assert invoke([*target, "load-model", "--file", str(model), "--prefix", "m_",
                   "--json"])["names"] == ["m_crate"]
    assert invoke([*target, "load-model", "--path", str(model), "--format", "mjcf",
                   "--prefix", "n_", "--json"])["names"] == ["n_crate"]
    sources = {e["name"]: e["source"] for e in invoke([*target, "entities", "--json"])}
    assert sources == {"m_crate": "model", "n_crate": "model"}


def test_load_model_from_a_file_finds_the_meshes_beside_it(target: list[str]) -> None:
    """kuka_iiwa/model.urdf names meshes/link_0.obj and so on: its own folder is searched
    without --search-path (issue 33)."""
    import pybullet_data

    urdf = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
    loaded = invoke([*target, "load-model", "--file", str(urdf), "--prefix", "k_", "--json"])
    assert "k_lbr_iiwa_link_7" in loaded["names"]


def test_load_model_needs_one_source_and_a_known_format(target: list[str],
                                                        tmp_path: Path) -> None:
    odd = tmp_path / "crate.model"
    odd.write_text(MODEL)
    assert run([*target, "load-model"]).exit_code == 2
    unknown = run([*target, "load-model", "--file", str(odd)])
    assert unknown.exit_code == 2 and "give --format" in flat(unknown.output)
    binary = tmp_path / "binary.xml"
    binary.write_bytes(b"\xff\xfe\x00<mujoco")
    unreadable = run([*target, "load-model", "--file", str(binary)])
    assert unreadable.exit_code == 2 and "cannot be read as text" in flat(unreadable.output)


@pytest.fixture
def restored(target: list[str]) -> Iterator[list[str]]:
    """The shared MuJoCo daemon, put back on MuJoCo after a test that switches engines."""
    yield target
    invoke([*target, "load-world", "mujoco", "--json"])


def test_load_world_switches_engine_with_params(restored: list[str]) -> None:
    status = invoke([*restored, "load-world", "pybullet", "timestep=0.004", "--json"])
    assert status["engine"] == "pybullet" and status["timestep"] == 0.004
    assert status["state"] == "stopped" and status["entity_count"] == 0
    capabilities = invoke([*restored, "capabilities", "--json"])
    assert capabilities["engine"] == "pybullet"
