"""galton-client calibrate's command line: bounds, defaults and a recording checked before
anything is sent (exit 2 with the reason)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.cli import NOWHERE, flat, run

from galton.client.sdk.calibration import bounds_for, observed_in
from galton.client.sdk.recording import Recording
from galton.protocol import EntityInfo, InvalidArgumentError


def recording(tmp_path: Path) -> Path:
    infos = [EntityInfo("ground", "plane", (50.0, 50.0), static=True),
             EntityInfo("box", "box", (0.05, 0.05, 0.05))]
    poses = np.tile([0, 0, 0, 0, 0, 0, 1.0], (3, 2, 1))
    path = tmp_path / "rec.npz"
    Recording(infos, np.array([0.0, 0.1, 0.1]), poses).save(path)
    return path


def test_a_recording_gives_its_moving_bodies_each_time_once(tmp_path: Path) -> None:
    seen = observed_in(Recording.load(recording(tmp_path)))
    assert seen.names == ["box"]
    assert seen.times.tolist() == [0.0, 0.1] and seen.poses.shape == (2, 1, 7)


def test_bounds_default_per_property_and_must_name_fitted_parameters() -> None:
    assert bounds_for(["box.friction", "gravity"], {"gravity": (9.0, 10.0)}) == {
        "box.friction": (0.0, 2.0), "gravity": (9.0, 10.0)}
    with pytest.raises(InvalidArgumentError, match="not fitted"):
        bounds_for(["box.friction"], {"ball.mass": (1.0, 2.0)})


@pytest.mark.parametrize("bounds", ["box.friction=1", "box.friction=a:b", "=0:1"])
def test_bad_bounds_exit_2_before_anything_is_sent(tmp_path: Path, bounds: str) -> None:
    result = run([*NOWHERE, "calibrate", str(recording(tmp_path)), "--fit", "box.friction",
                  "--bounds", bounds])
    assert result.exit_code == 2
    assert "--bounds" in result.output or "bounds" in result.output


def test_a_file_that_is_no_recording_exits_2(tmp_path: Path) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"nothing")
    result = run([*NOWHERE, "calibrate", str(bad), "--fit", "box.friction"])
    assert result.exit_code == 2 and "no recording" in flat(result.output)
