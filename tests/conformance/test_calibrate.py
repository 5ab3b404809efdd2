"""calibrate on every engine: a box's friction fitted to a short prediction of its slide
(a small search), the world untouched unless asked, and the typed refusals."""

from __future__ import annotations

import numpy as np
import pytest
from support_calibration import slide_and_bounce

from galton.client import Client
from galton.protocol import FeatureUnsupportedError, InvalidArgumentError, NotFoundError

TRUE_FRICTION = 0.3
HORIZON_S = 0.4
SEEN_EVERY_S = 1 / 30


def test_a_friction_is_fitted_to_what_was_seen(sim: Client, engine: str) -> None:
    moving = slide_and_bounce(sim, engine, TRUE_FRICTION, 0.5, ball=False)
    seen = sim.predict(HORIZON_S, every=SEEN_EVERY_S, read=moving)
    twists = seen.twists[0]
    sim.update(["box"], friction=0.8)
    result = sim.calibrate({"box.friction": (0.05, 1.5)}, moving, seen.times, seen.poses,
                           twists=twists, max_predictions=40, population=6)
    assert result.error_after < result.error_before / 5
    assert abs(result.fitted["box.friction"] - TRUE_FRICTION) < 0.1 * TRUE_FRICTION
    low, high = result.intervals["box.friction"]
    assert low <= result.fitted["box.friction"] <= high
    assert 2 <= result.predictions <= 40 and not result.applied
    assert sim.list(name="box")[0].friction == pytest.approx(0.8)  # untouched
    applied = sim.calibrate({"box.friction": (0.05, 1.5)}, moving, seen.times, seen.poses,
                            twists=twists, max_predictions=6, apply=True)
    assert applied.applied
    assert sim.list(name="box")[0].friction == pytest.approx(applied.fitted["box.friction"])


def test_what_cannot_be_fitted_is_refused_by_name(sim: Client, engine: str) -> None:
    moving = slide_and_bounce(sim, engine, TRUE_FRICTION, 0.5, ball=False)
    times, poses = np.array([0.0, 0.1]), np.tile(sim.get_states(moving).poses, (2, 1, 1))
    with pytest.raises(FeatureUnsupportedError, match="box.damping") as refused:
        sim.calibrate({"box.damping": (0.0, 1.0)}, moving, times, poses)
    assert refused.value.details["parameter"] == "box.damping"
    with pytest.raises(NotFoundError, match="crate"):
        sim.calibrate({"crate.friction": (0.0, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="low < high"):
        sim.calibrate({"box.friction": (1.0, 0.5)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="restitution"):
        sim.calibrate({"box.restitution": (0.0, 1.5)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="did you mean"):
        sim.calibrate({"box.frict": (0.0, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="slab.*static|static"):
        sim.calibrate({"ground.mass": (0.1, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="increasing"):
        sim.calibrate({"box.friction": (0.1, 1.0)}, moving, times[::-1], poses)
    assert sim.list(name="box")[0].friction == pytest.approx(TRUE_FRICTION)
