"""Bar `calibrate` (issue 53): a recording of a box sliding at friction 0.3 and a ball
bouncing at restitution 0.5, fitted by `galton-client calibrate --json` from a world at 0.8
and 0.1: both recovered within 10 %, the position error down at least 10 times, and the
predictions it took said. Slow (a full search): python -m pytest -m slow
tests/test_calibrate_bar.py."""

from __future__ import annotations

from pathlib import Path

import pytest
from support.calibration import slide_and_bounce
from support.cli import invoke, target_of

from galton.client import Client, EmbeddedDaemon
from galton.client.sdk.recording import Recorder

TRUE = {"box.friction": 0.3, "ball.restitution": 0.5}
RECORD_S = 1.0
RATE_HZ = 60.0


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_a_recording_is_fitted_back(daemon: EmbeddedDaemon, engine: str, tmp_path: Path
                                    ) -> None:
    path = tmp_path / "slide.npz"
    with Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        sim.load_world(engine)
        slide_and_bounce(sim, engine, TRUE["box.friction"], TRUE["ball.restitution"])
        with Recorder(sim, path, rate=RATE_HZ) as recorder:
            sim.play(1.0)
            assert recorder.wait_for(round(RECORD_S * RATE_HZ), timeout=60.0)
            sim.pause()
        sim.update(["box"], friction=0.8)
        sim.update(["ball"], restitution=0.1)
    out = invoke([*target_of(daemon), "calibrate", str(path), "--fit",
                  "box.friction,ball.restitution", "--bounds",
                  "box.friction=0.05:1.5,ball.restitution=0:0.95", "--json"])
    assert set(out) == {"fitted", "intervals", "error_before", "error_after", "predictions"}
    for name, value in TRUE.items():
        assert out["fitted"][name] == pytest.approx(value, rel=0.1), out
        low, high = out["intervals"][name]
        assert low <= out["fitted"][name] <= high
    assert out["error_after"] * 10 <= out["error_before"], out
    assert out["predictions"] > 1
    print(f"{engine}: {out}")
