"""galton-client view in a real browser: a daemon, a scene of red balls, the view process,
and Debian's headless Chromium taking screenshots of the page (software WebGL)."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from support.browser import CHROMIUM, Browser

from galton.client import Client, plane, spheres

pytest.importorskip("viser", reason="the [view] extra is not installed")
pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium-headless-shell is missing (.ci/run installs it: "
                             "apt-get install -y chromium-headless-shell)")

READY_TIMEOUT_S = 180.0  # viser's import alone takes seconds on a loaded machine
DRAWN_TIMEOUT_S = 150.0  # software WebGL on a loaded machine is slow
WIDTH, HEIGHT = 800, 600
PANEL_LEFT = 0.575  # viser's control panel covers the page right of this (at 800 px wide)
MIN_PIXELS = 25  # red pixels that make the five balls (at half scale)
AXES_CORNER = 0.15  # viser draws an axes gizmo in the bottom-left corner
LOADS = 10  # the page loaded this many times in a row must show its panel each time
PANEL_TIMEOUT_S = 60.0  # one load's panel, on a loaded machine (seconds when quiet)
PANEL_WORDS = ("sim time", "Play", "Pause", "Step 100", "Reset", "Predict 1 s",
               "Side worlds (ghosts)", "compare: anomaly score")
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


def _red_pixels(image: np.ndarray) -> np.ndarray:
    """(row, column) of the red balls' pixels in the 3-D view (left of the panel), in
    fractions of the page's height and width (the browser draws at a reduced scale)."""
    height, width = image.shape[:2]
    red, green, blue = image[..., 0], image[..., 1], image[..., 2]
    mask = (red > 120) & (green < 90) & (blue < 90) & (red > 2 * green)
    mask[:, int(PANEL_LEFT * width):] = False
    corner = int(AXES_CORNER * height)
    mask[-corner:, :corner] = False  # the axes gizmo's red x axis
    return np.argwhere(mask) / np.array([height, width])


@pytest.mark.timeout(600)  # software WebGL: a screenshot takes seconds on a loaded machine
def test_the_page_draws_the_red_balls_and_they_fall_while_playing(
        mujoco_sim: Client, view_url: str) -> None:
    sim = mujoco_sim
    sim.spawn(plane())
    names = [f"red_{i}" for i in range(5)]
    sim.spawn(spheres(names, [[0.15 * i - 0.3, 0.0, 2.0] for i in range(5)], radius=0.06,
                      tags=["red"]))
    sim.step(1)
    before = sim.get_states(names)
    with Browser(view_url, WIDTH, HEIGHT) as browser:
        paused = _red_pixels(browser.wait_for(lambda image: len(_red_pixels(image)) > MIN_PIXELS,
                                              DRAWN_TIMEOUT_S))
        browser.text_until(_shows_panel, PANEL_TIMEOUT_S)  # the panel beside the scene
        after = sim.get_states(names)
        assert after.step == before.step  # opening the page never disturbs the world
        np.testing.assert_array_equal(after.poses, before.poses)
        rows, columns = paused[:, 0], paused[:, 1]
        # Framed from the front: the row of balls is centred left to right, above ground.
        assert abs(columns.mean() - 0.5) < 0.15
        assert rows.mean() < 0.75
        sim.play()  # 2 m of fall take 0.64 s; then they rest on the plane, lower still
        try:
            browser.wait_for(lambda image: _fell(_red_pixels(image), rows.mean()),
                             DRAWN_TIMEOUT_S)
            assert "playing" in browser.text_until(_shows_panel, PANEL_TIMEOUT_S)
        finally:
            sim.pause()
    assert sim.get_states(names).poses[:, 2].max() < 2.0


def _fell(pixels: np.ndarray, first_row: float) -> bool:
    """The balls are drawn, lower on the page than they were."""
    return len(pixels) > MIN_PIXELS and pixels[:, 0].mean() > first_row + 0.02


def _shows_panel(text: str) -> bool:
    """The operator's panel is drawn: the clock, the buttons, the ghosts' switch, the chart."""
    return all(word in text for word in PANEL_WORDS)


@pytest.mark.timeout(600)
def test_the_panel_is_drawn_on_every_load(mujoco_sim: Client, view_url: str) -> None:
    """Loaded ten times in a row (a fresh page and connection each time), the page shows
    its whole panel every time, and loading it changes nothing in the world."""
    mujoco_sim.spawn(spheres(["red_0"], [[0.0, 0.0, 1.0]], radius=0.06, tags=["red"]))
    mujoco_sim.step(1)
    before = mujoco_sim.get_states(["red_0"])
    with Browser(view_url, WIDTH, HEIGHT) as browser:
        for load in range(LOADS):
            if load:
                browser.reload()
            text = browser.text_until(_shows_panel, PANEL_TIMEOUT_S)
            assert f"step {before.step}" in text, f"load {load}: {text!r}"
    after = mujoco_sim.get_states(["red_0"])
    assert after.step == before.step
    np.testing.assert_array_equal(after.poses, before.poses)
