"""calibrate on every engine: a box's friction fitted to a short prediction of its slide
(a small search), the world untouched unless asked, and the typed refusals."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pytest
from support import companion
from support.calibration import slide_and_bounce

from galton.client import Client, spheres
from galton.protocol import (
    InvalidArgumentError,
    NotFoundError,
    OperationFailedError,
)

TRUE_FRICTION = 0.3
HORIZON_S = 0.4
SEEN_EVERY_S = 1 / 30


def test_a_friction_is_fitted_to_what_was_seen(sim: Client, engine: str) -> None:
    moving = slide_and_bounce(sim, engine, TRUE_FRICTION, 0.5, ball=False)
    seen = sim.predict(HORIZON_S, every=SEEN_EVERY_S, read=moving)
    twists = seen.twists[0]
    sim.update(["box"], friction=0.8)
    result = sim.calibrate({"box.friction": (0.05, 1.5)}, moving, seen.times, seen.poses,
                           twists=twists, max_predictions=30, population=6)
    assert result.error_after < result.error_before / 5
    assert abs(result.fitted["box.friction"] - TRUE_FRICTION) < 0.1 * TRUE_FRICTION
    low, high = result.intervals["box.friction"]
    assert low <= result.fitted["box.friction"] <= high
    assert 2 <= result.predictions <= 30 and not result.applied
    assert sim.list(name="box")[0].friction == pytest.approx(0.8)  # untouched
    applied = sim.calibrate({"box.friction": (0.05, 1.5)}, moving, seen.times, seen.poses,
                            twists=twists, max_predictions=6, apply=True)
    assert applied.applied
    assert sim.list(name="box")[0].friction == pytest.approx(applied.fitted["box.friction"])


def test_what_cannot_be_fitted_is_refused_by_name(sim: Client, engine: str) -> None:
    moving = slide_and_bounce(sim, engine, TRUE_FRICTION, 0.5, ball=False)
    times, poses = np.array([0.0, 0.1]), np.tile(sim.get_states(moving).poses, (2, 1, 1))
    with pytest.raises(NotFoundError, match="no joint 'box'"):  # a body has no damping
        sim.calibrate({"box.damping": (0.0, 1.0)}, moving, times, poses)
    with pytest.raises(NotFoundError, match="crate"):
        sim.calibrate({"crate.friction": (0.0, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="low < high"):
        sim.calibrate({"box.friction": (1.0, 0.5)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="restitution"):
        sim.calibrate({"box.restitution": (0.0, 1.5)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="did you mean"):
        sim.calibrate({"box.frict": (0.0, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="static"):
        sim.calibrate({"ground.mass": (0.1, 1.0)}, moving, times, poses)
    with pytest.raises(InvalidArgumentError, match="increasing"):
        sim.calibrate({"box.friction": (0.1, 1.0)}, moving, times[::-1], poses)
    assert sim.list(name="box")[0].friction == pytest.approx(TRUE_FRICTION)


@pytest.mark.parametrize("engine", ["mujoco"])
def test_a_long_calibration_reports_progress_and_ends_at_pause(sim: Client) -> None:
    """Engine independent: a `calibration` event per generation, and `pause` ends the
    search as it ends a prediction."""
    moving = slide_and_bounce(sim, sim.status().engine, TRUE_FRICTION, 0.5, ball=False)
    seen = sim.predict(HORIZON_S, every=SEEN_EVERY_S, read=moving)
    sim.update(["box"], friction=0.8)
    progress: list[dict[str, Any]] = []
    paused = threading.Event()

    def on_event(event: dict[str, Any]) -> None:
        if event.get("kind") == "calibration":
            progress.append(event)
            paused.set()

    def pause_at_first_generation() -> None:
        assert paused.wait(30)
        with companion(sim) as other:
            other.pause()

    with sim.on_event(on_event):
        thread = threading.Thread(target=pause_at_first_generation)
        thread.start()
        try:
            with pytest.raises(OperationFailedError, match="interrupted"):
                sim.calibrate({"box.friction": (0.05, 1.5)}, moving, seen.times, seen.poses,
                              twists=seen.twists[0], max_predictions=100_000, timeout=120)
        finally:
            thread.join(30)
    first = progress[0]
    assert first["generation"] == 0 and first["predictions"] == 13  # the design: 2 x 6
    assert set(first) >= {"world", "best_error", "spread"}


@pytest.mark.parametrize("engine", ["mujoco", "ode"])  # set_params' gravity: engine-blind
def test_gravity_is_fitted_and_a_mass_it_cannot_see_stays_loose(sim: Client) -> None:
    """A ball in free fall pins gravity; its mass, which free fall does not show, keeps a
    wide interval (the search's spread says what the observation cannot tell). On the two
    engines whose copies are cheapest (100 predictions)."""
    sim.spawn(spheres(["ball"], [[0.0, 0.0, 2.0]], 0.05, mass=0.2))
    seen = sim.predict(0.3, every=0.02, read=["ball"])
    sim.set_params({"gravity": [0.0, 0.0, -5.0]})
    result = sim.calibrate({"gravity": (1.0, 20.0), "ball.mass": (0.05, 1.0)}, ["ball"],
                           seen.times, seen.poses, twists=seen.twists[0], max_predictions=100)
    assert result.fitted["gravity"] == pytest.approx(9.81, rel=0.05)
    assert result.error_after * 10 < result.error_before
    gravity_width = np.diff(result.intervals["gravity"])[0] / 19.0
    mass_width = np.diff(result.intervals["ball.mass"])[0] / 0.95
    assert mass_width > 3 * gravity_width, result.intervals
    assert sim.get_params()["gravity"][2] == pytest.approx(-5.0)  # not applied
