"""Sim to sim (issue 53): PyBullet fitted to a recording made on MuJoCo. The same call as
on its own recording; what the fitted values are is PyBullet's answer to "which of my
parameters behave like that?" (each engine's contact rule differs: docs/PHYSICS.md,
"Calibration"). Slow: python -m pytest -m slow tests/test_calibrate_across.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.calibration import slide_and_bounce
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon
from galton.client.sdk.calibration import observed_in
from galton.client.sdk.recording import Recorder, Recording

RECORD_S, RATE_HZ = 1.0, 60.0
FIT = {"box.friction": (0.05, 1.5), "ball.restitution": (0.0, 0.95)}


def record(daemon: EmbeddedDaemon, path: Path) -> None:
    with Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        sim.load_world(daemon.engine)
        slide_and_bounce(sim, daemon.engine, 0.3, 0.5)
        with Recorder(sim, path, rate=RATE_HZ) as recorder:
            sim.play(1.0)
            assert recorder.wait_for(round(RECORD_S * RATE_HZ), timeout=60.0)
            sim.pause()


@pytest.mark.slow
def test_pybullet_is_fitted_to_a_mujoco_recording(daemons: dict[str, EmbeddedDaemon],
                                                  tmp_path: Path) -> None:
    path = tmp_path / "mujoco.npz"
    record(start_daemon(daemons, "mujoco"), path)
    bullet = start_daemon(daemons, "pybullet")
    with Client(bullet.instance, bullet.endpoint, timeout=120.0) as sim:
        sim.load_world("pybullet")
        slide_and_bounce(sim, "pybullet", 0.8, 0.1)
        seen = observed_in(Recording.load(path))
        fit = sim.calibrate(FIT, seen.names, seen.times, seen.poses)
    print(f"pybullet fitted to mujoco: {fit}")
    assert fit.error_after * 5 <= fit.error_before
    assert fit.fitted["box.friction"] == pytest.approx(0.3, rel=0.25)
