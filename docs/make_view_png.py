"""Make docs/img/view.png, the README's picture of `galton-client view`: a MuJoCo daemon,
the small Galton board with its balls falling, a fork of the world as a ghost, the page
drawn by headless Chromium (software WebGL) driven as the view's tests drive it, over
DevTools (tests/support/browser.py): the picture is taken once the page's text shows the
panel and a screenshot shows both the balls in the scene and the panel's buttons, not after
a guessed delay (a one-shot ``--screenshot`` run photographs the page before viser has
applied its panel, which it does in the 3-D view's render loop). viser's notice that WebGL
runs in software (true of headless Chromium, not of a user's browser) is closed first.

    python docs/make_view_png.py [--out docs/img/view.png]
"""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the browser driver the view's tests use

from support.browser import Browser  # noqa: E402

from galton.analysis.board import BoardSpec  # noqa: E402
from galton.analysis.board_release import perturbation  # noqa: E402
from galton.client import Client, EmbeddedDaemon, wait_for_daemon  # noqa: E402
from galton.client.bench.build import ball_group, ball_names, board_groups  # noqa: E402

BOARD = ROOT / "client" / "boards" / "small.toml"
CLI = str(Path(sys.executable).with_name("galton-client"))
WIDTH, HEIGHT = 1200, 800
DRAWN_TIMEOUT_S = 300.0  # software WebGL on a loaded machine
PANEL_WORDS = ("sim time", "Play", "Predict 1 s", "compare: anomaly score")
PANEL_LEFT = 0.7  # the panel covers the page right of this at 1200 px
MIN_BALL_PIXELS = 200
MIN_BUTTON_PIXELS = 2000  # five buttons of about 280 x 25 px
# Close viser's "Software WebGL rendering detected" notice (Mantine's notification): its
# close button, found by the notice's text; returns whether one was closed.
CLOSE_SOFTWARE_NOTICE = """(() => {
  const notices = [...document.querySelectorAll('.mantine-Notification-root')]
    .filter((n) => n.innerText.includes('Software WebGL'));
  notices.forEach((n) => n.querySelector('button')?.click());
  return notices.length > 0;
})()"""


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def ball_pixels(image: np.ndarray) -> int:
    """Red pixels (balls) in the 3-D view, left of the panel."""
    scene = image[:, : int(PANEL_LEFT * image.shape[1])]
    red, green, blue = scene[..., 0], scene[..., 1], scene[..., 2]
    return int(((red > 120) & (green < 90) & (blue < 90)).sum())


def button_pixels(image: np.ndarray) -> int:
    """The operator's blue buttons' pixels in the panel."""
    panel = image[:, int(PANEL_LEFT * image.shape[1]):]
    red, green, blue = panel[..., 0], panel[..., 1], panel[..., 2]
    return int(((blue > 180) & (red < 80) & (green > 100) & (green < 170)).sum())


def drawn(image: np.ndarray) -> bool:
    """The scene's balls and the panel's buttons both in the picture."""
    return ball_pixels(image) > MIN_BALL_PIXELS and button_pixels(image) > MIN_BUTTON_PIXELS


def photograph(url: str, out: Path) -> None:
    from PIL import Image
    with Browser(url, WIDTH, HEIGHT, scale=1.0) as browser:
        browser.text_until(lambda text: all(w in text for w in PANEL_WORDS), DRAWN_TIMEOUT_S)
        if browser.evaluate(CLOSE_SOFTWARE_NOTICE):
            browser.text_until(lambda text: "Software WebGL" not in text, DRAWN_TIMEOUT_S)
        image = browser.wait_for(drawn, DRAWN_TIMEOUT_S)
    Image.fromarray(image.astype(np.uint8)).save(out)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "view.png")
    out = parser.parse_args().out.resolve()
    board = BoardSpec.load(BOARD)
    with EmbeddedDaemon("mujoco", instance="view-picture") as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30) as sim:
        wait_for_daemon(sim.session, daemon.instance, 30)
        sim.spawn(*board_groups(board, "mujoco"))
        shake = perturbation(board, 0, 0, board.ball.count)
        names = ball_names(board.ball.count)
        sim.spawn(ball_group(board, "mujoco", names, shake.release.positions))
        sim.run_until(0.6)
        sim.fork_world("ahead")
        sim.world("ahead").run_until(0.9)  # what the model expects, a little ahead
        port = free_port()
        view = subprocess.Popen([CLI, "--connect", daemon.endpoint, "--instance",
                                 daemon.instance, "view", "--port", str(port)],
                                stderr=subprocess.PIPE, text=True)
        try:
            assert view.stderr is not None
            while "serving" not in view.stderr.readline():
                pass
            photograph(f"http://127.0.0.1:{port}", out)
        finally:
            view.terminate()
            view.wait(30)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
