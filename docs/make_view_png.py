"""Make docs/img/view.png, the README's picture of `galton-client view`: a MuJoCo daemon,
the small Galton board with its balls falling, a fork of the world as a ghost, the page
drawn by headless Chromium (software WebGL).

    python docs/make_view_png.py [--out docs/img/view.png]
"""

from __future__ import annotations

import argparse
import socket
import subprocess
import sys
from pathlib import Path

from galton.analysis.board import BoardSpec
from galton.analysis.board_release import perturbation
from galton.client import Client, EmbeddedDaemon, wait_for_daemon
from galton.client.bench.build import ball_group, ball_names, board_groups

BOARD = Path(__file__).resolve().parents[1] / "client" / "boards" / "small.toml"
CLI = str(Path(sys.executable).with_name("galton-client"))


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path, default=Path("docs/img/view.png"))
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
            subprocess.run(["chromium-headless-shell", "--no-sandbox",
                            "--enable-unsafe-swiftshader", "--use-gl=angle",
                            "--use-angle=swiftshader", "--window-size=1200,800",
                            "--timeout=10000", f"--screenshot={out}",
                            f"http://127.0.0.1:{port}"], check=True, capture_output=True,
                           timeout=180)
        finally:
            view.terminate()
            view.wait(30)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
