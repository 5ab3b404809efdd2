"""galton-client's perception commands through typer's runner, against a real daemon:
render writes PNG (and .npy) files, a named camera renders by name, raycast and contacts
print what the SDK returns, and bad command lines or cameras fail with one clear line."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from support.cli import flat, invoke, run, target_of
from support.perception import known_scene
from support.worlds import clean

from galton.client import Client, EmbeddedDaemon, boxes
from galton.protocol.png import decode_png

TOP = ["--eye", "0,0,3", "--target", "0,0,0", "--up", "0,1,0", "--fov", "60",
       "--size", "64x48"]


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> Iterator[list[str]]:
    with clean(mujoco_sim) as sim:
        known_scene(sim)
        yield target_of(daemons["mujoco"])


def test_render_writes_pictures(target: list[str], tmp_path: Path) -> None:
    frame, depth, seg = tmp_path / "frame.png", tmp_path / "depth.npy", tmp_path / "seg.png"
    found = invoke([*target, "render", "--out", str(frame), "--depth-out", str(depth),
                    "--seg-out", str(seg), *TOP, "--json"])
    assert (found["width"], found["height"]) == (64, 48)
    assert found["files"] == [str(frame), str(depth), str(seg)]
    assert set(found["seen"]) == {"ground", "box", "ball"}
    assert decode_png(frame.read_bytes()).shape == (48, 64, 3)
    metres = np.load(depth)
    # the ground in a corner: 3 m along the view axis (depth is not the distance)
    assert metres.dtype == np.float32 and metres[0, 0] == pytest.approx(3.0, abs=2e-3)
    labels = decode_png(seg.read_bytes())
    assert labels.dtype == np.uint16 and labels.min() >= 1  # everything sees the ground
    human = run([*target, "render", "--out", str(frame), *TOP])
    assert human.exit_code == 0 and "64x48" in flat(human.output)


def test_depth_png_holds_millimetres(target: list[str], tmp_path: Path) -> None:
    depth = tmp_path / "depth.png"
    invoke([*target, "render", "--depth-out", str(depth), *TOP, "--json"])
    millimetres = decode_png(depth.read_bytes())
    assert millimetres.dtype == np.uint16
    assert abs(int(millimetres[24, 32]) - 3000) <= 2  # the ground under the camera


def test_named_cameras(target: list[str], tmp_path: Path) -> None:
    made = invoke([*target, "add-camera", "top", *TOP, "--outputs", "rgb,depth", "--json"])
    assert made[0]["name"] == "top" and made[0]["outputs"] == ["rgb", "depth"]
    assert [c["name"] for c in invoke([*target, "cameras", "--json"])] == ["top"]
    frame = tmp_path / "frame.png"
    found = invoke([*target, "render", "--camera", "top", "--out", str(frame), "--json"])
    assert found["width"] == 64 and frame.exists()
    assert "top" in flat(run([*target, "cameras"]).output)
    assert invoke([*target, "remove-camera", "top", "--json"]) == {"removed": "top"}
    assert "no camera" in run([*target, "cameras"]).output
    gone = run([*target, "remove-camera", "top"])
    assert gone.exit_code == 1 and "NOT_FOUND" in gone.output


def test_raycast_prints_each_rays_hit(target: list[str]) -> None:
    rows = invoke([*target, "raycast", "--from", "0.5,0,1,0,0,1", "--dir", "0,0,-1,0,0,1",
                   "--json"])
    assert rows[0]["entity"] == "box" and rows[0]["point"] == pytest.approx([0.5, 0, 0.2])
    assert rows[0]["distance"] == pytest.approx(0.8)
    assert rows[1] == {"hit": False, "entity": None, "point": None, "normal": None,
                       "distance": None}
    ends = invoke([*target, "raycast", "--from", "-0.5,0,1", "--to", "-0.5,0,0", "--json"])
    assert ends[0]["entity"] == "ball" and ends[0]["normal"] == pytest.approx([0, 0, 1])
    human = run([*target, "raycast", "--from", "0,0,1", "--dir", "0,0,1"])
    assert human.exit_code == 0 and "(miss)" in human.output


def test_contacts(mujoco_sim: Client, target: list[str]) -> None:
    mujoco_sim.spawn(boxes(["crate"], [[0, 1, 0.1]], [0.1] * 3, restitution=0.0))
    assert invoke([*target, "contacts", "--json"]) == []
    assert "no contact" in run([*target, "contacts"]).output
    invoke([*target, "step", "50", "--json"])
    rows = invoke([*target, "contacts", "crate", "--json"])
    assert rows and all({r["a"], r["b"]} == {"crate", "ground"} for r in rows)
    assert "crate" in flat(run([*target, "contacts"]).output)


@pytest.mark.parametrize(("args", "message"), [
    (["render", *TOP], "--out"),
    (["render", "--out", "x.png", "--eye", "0,0,3"], "--target"),
    (["render", "--out", "x.png", "--eye", "0,0", "--target", "0,0,0"], "x,y,z"),
    (["render", "--out", "x.png", *TOP[:-1], "64by48"], "WIDTHxHEIGHT"),
    (["raycast", "--from", "0,0,1"], "exactly one"),
    (["raycast", "--from", "0,0", "--dir", "0,0,1"], "rows of x,y,z"),
])
def test_bad_command_lines_exit_2(args: list[str], message: str) -> None:
    result = run(args)
    assert result.exit_code == 2 and message in flat(result.output)


def test_a_bad_camera_fails_with_one_line(target: list[str], tmp_path: Path) -> None:
    result = run([*target, "render", "--out", str(tmp_path / "x.png"), *TOP[:-1], "0x48"])
    assert result.exit_code == 1 and "INVALID_ARGUMENT" in result.output
    assert "width" in result.output and not (tmp_path / "x.png").exists()
