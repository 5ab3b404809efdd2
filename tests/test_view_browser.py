"""galton-client view in a real browser: a daemon, a scene of red balls, the view process,
and Debian's headless Chromium taking screenshots of the page (software WebGL)."""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from galton.client import Client, plane, spheres

pytest.importorskip("viser", reason="the [view] extra is not installed")
CHROMIUM = shutil.which("chromium-headless-shell")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium-headless-shell is missing (.ci/run installs it: "
                             "apt-get install -y chromium-headless-shell)")

READY_TIMEOUT_S = 60.0
SHOT_TIMEOUT_S = 120.0
WIDTH, HEIGHT = 800, 600
PANEL_LEFT = 460  # viser's control panel covers the page right of this (at 800 px wide)
AXES_CORNER = 90  # viser draws an axes gizmo in the bottom-left corner
CLI = str(Path(sys.executable).with_name("galton-client"))


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


@pytest.fixture
def view_url(mujoco_sim: Client, daemons: dict[str, object]) -> Iterator[str]:
    """`galton-client view` on the session's MuJoCo daemon, once it says it serves."""
    daemon = daemons["mujoco"]
    port = _free_port()
    process = subprocess.Popen(
        [CLI, "--connect", daemon.endpoint, "--instance", mujoco_sim.instance,  # type: ignore[attr-defined]
         "view", "--port", str(port), "--rate", "20"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert process.stderr is not None
    ready = threading.Event()

    def read_lines() -> None:
        assert process.stderr is not None
        for line in process.stderr:
            if "serving http://" in line:
                ready.set()
    threading.Thread(target=read_lines, daemon=True).start()
    try:
        assert ready.wait(READY_TIMEOUT_S), "galton-client view did not say it serves"
        yield f"http://127.0.0.1:{port}"
    finally:
        process.terminate()
        code = process.wait(30)
        process.stderr.close()
        assert code == 0


def _screenshot(url: str, path: Path) -> np.ndarray:
    """The page as Chromium draws it once the view has sent the scene (RGB, H x W x 3)."""
    assert CHROMIUM is not None
    subprocess.run(
        [CHROMIUM, "--no-sandbox", "--enable-unsafe-swiftshader", "--use-gl=angle",
         "--use-angle=swiftshader", f"--window-size={WIDTH},{HEIGHT}",
         "--virtual-time-budget=5000", f"--screenshot={path}", url],
        check=True, capture_output=True, timeout=SHOT_TIMEOUT_S,
        env={**os.environ, "HOME": str(path.parent)})
    from PIL import Image
    return np.asarray(Image.open(path).convert("RGB")).astype(int)


def _red_pixels(image: np.ndarray) -> np.ndarray:
    """(row, column) of the red balls' pixels in the 3-D view (left of the panel)."""
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    mask = (red > 120) & (green < 90) & (blue < 90) & (red > 2 * green)
    mask[:, PANEL_LEFT:] = False
    mask[-AXES_CORNER:, :AXES_CORNER] = False  # the axes gizmo's red x axis
    return np.argwhere(mask)


def test_the_page_draws_the_red_balls_and_they_fall_while_playing(
        mujoco_sim: Client, view_url: str, tmp_path: Path) -> None:
    sim = mujoco_sim
    sim.spawn(plane())
    names = [f"red_{i}" for i in range(5)]
    sim.spawn(spheres(names, [[0.15 * i - 0.3, 0.0, 2.0] for i in range(5)], radius=0.06,
                      tags=["red"]))
    sim.step(1)
    before = sim.get_states(names)
    paused = _red_pixels(_screenshot(view_url, tmp_path / "paused.png"))
    after = sim.get_states(names)
    assert after.step == before.step  # opening the page never disturbs the world
    np.testing.assert_array_equal(after.poses, before.poses)
    assert len(paused) > 100, "no red balls drawn"
    rows, columns = paused[:, 0], paused[:, 1]
    # Framed from the front: the row of balls is centred left to right, above the ground.
    assert abs(columns.mean() - WIDTH / 2) < 120
    assert rows.mean() < HEIGHT * 0.75

    sim.play(rtf=0.02)  # 2 m of fall take 0.64 s of sim time: 32 s of wall time
    try:
        playing = _red_pixels(_screenshot(view_url, tmp_path / "playing.png"))
    finally:
        sim.pause()
    assert sim.get_states(names).poses[:, 2].max() < 2.0
    assert len(playing) > 100
    assert playing[:, 0].mean() > rows.mean() + 3, "the balls did not move down the page"
