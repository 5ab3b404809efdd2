"""compare's surprise trigger over a real daemon: comparisons in a row above the threshold
are counted per world, the one that makes the streak its window suggests a calibration
(in its reply and in a `calibration_suggested` event) once per streak, an unsurprising
comparison ends the streak, and a bad trigger is refused without counting; a trigger's
``calibrate`` starts the daemon's own calibration (events, ended by pause)."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pytest

from galton.client import Client, spheres
from galton.protocol import InvalidArgumentError, NotFoundError

TRIGGER = (3.0, 3)  # threshold, window
SEEN_RIGHT = np.array([[0.0, 0.0, 1.0, 0, 0, 0, 1.0]])
SEEN_WRONG = np.array([[0.1, 0.0, 1.0, 0, 0, 0, 1.0]])  # 10 cm off: a score of 10


@pytest.mark.parametrize("engine", ["mujoco"])  # the streak is the daemon's: engine-blind
def test_a_streak_of_surprises_suggests_a_calibration(sim: Client) -> None:
    sim.spawn(spheres(["a"], [[0, 0, 1]], 0.05, static=True))
    suggested: list[dict[str, Any]] = []
    arrived = threading.Event()

    def on_event(event: dict[str, Any]) -> None:
        if event.get("kind") == "calibration_suggested":
            suggested.append(event)
            arrived.set()

    def compare(seen: np.ndarray) -> tuple[int | None, bool]:
        found = sim.compare(["a"], seen, sigma_position=0.01, trigger=TRIGGER)
        return found.streak, found.suggested

    with sim.on_event(on_event):
        assert [compare(SEEN_WRONG), compare(SEEN_WRONG)] == [(1, False), (2, False)]
        assert compare(SEEN_RIGHT) == (0, False)  # the streak ends
        assert sim.compare(["a"], SEEN_WRONG).streak is None  # no trigger: not counted
        assert [compare(SEEN_WRONG) for _ in range(4)] == [(1, False), (2, False),
                                                             (3, True), (4, False)]
        assert arrived.wait(30)
    event = suggested[0]
    assert event["names"] == ["a"] and event["streak"] == 3 and event["score"] > 3
    assert event["threshold"] == 3.0 and event["window"] == 3
    assert event["world"] == sim.status().world and np.isfinite(event["since"])


@pytest.mark.parametrize("engine", ["mujoco"])
def test_a_bad_trigger_is_refused_and_not_counted(sim: Client) -> None:
    sim.spawn(spheres(["a"], [[0, 0, 1]], 0.05, static=True))
    assert sim.compare(["a"], SEEN_WRONG, trigger=TRIGGER).streak == 1
    pose = SEEN_WRONG.tobytes()
    for bad in ({"threshold": 0.0, "window": 2}, {"threshold": 3.0, "window": 0},
                {"threshold": 3.0}, {"threshold": 3.0, "window": 2, "after": 1},
                {"threshold": float("nan"), "window": 2}):
        with pytest.raises(InvalidArgumentError, match="trigger"):
            sim.call("compare", {"names": ["a"], "poses": pose, "trigger": bad})
    assert sim.compare(["a"], SEEN_WRONG, trigger=TRIGGER).streak == 2
    sim.reset("state")
    assert sim.compare(["a"], SEEN_WRONG, trigger=TRIGGER).streak == 1  # reset: a new one


CALIBRATE = {"fit": {"ball.mass": (0.05, 1.0)}, "max_predictions": 20_000}


@pytest.mark.parametrize("engine", ["mujoco"])  # the daemon's job: engine-blind
def test_a_trigger_that_calibrates_starts_the_job_and_pause_ends_it(sim: Client) -> None:
    """With ``calibrate`` the comparison that makes the streak its window starts the
    daemon's own calibration over the streak's observations (``calibrating``, and a
    ``calibration_started`` event naming them); ``pause`` ends it as it ends any
    calibrate, and a ``calibration_finished`` event says so. While it runs, another
    streak's window starts none."""
    sim.spawn(spheres(["ball"], [[0, 0, 1.0]], 0.05, mass=0.2))
    events: dict[str, list[dict[str, Any]]] = {"calibration_started": [],
                                               "calibration_finished": []}
    finished = threading.Event()

    def on_event(event: dict[str, Any]) -> None:
        if event.get("kind") in events:
            events[event["kind"]].append(event)
            # the busy refusal's event comes first (at the compare); wait for the job's end
            if event["kind"] == "calibration_finished" and event.get("error") != "INCORRECT_STATE":
                finished.set()

    def compare() -> Any:
        sim.step(10)
        seen = sim.get_states(["ball"]).poses + np.array([0.1, 0, 0, 0, 0, 0, 0])
        return sim.compare(["ball"], seen, sigma_position=0.01, trigger=TRIGGER,
                           calibrate=CALIBRATE)

    with sim.on_event(on_event):
        assert [compare().calibrating for _ in range(2)] == [False, False]
        third = compare()
        assert third.suggested and third.calibrating
        here = sim.get_states(["ball"]).poses
        assert sim.compare(["ball"], here, trigger=TRIGGER).streak == 0  # the streak ends
        # a new streak of three while the job runs: its calibration is refused, busy
        others = [sim.compare(["ball"], SEEN_WRONG, trigger=TRIGGER, calibrate=CALIBRATE)
                  for _ in range(3)]
        assert others[-1].suggested and not others[-1].calibrating
        sim.pause()
        assert finished.wait(30)
    started = events["calibration_started"][0]
    assert started["names"] == ["ball"] and started["samples"] == 3
    assert started["fit"] == {"ball.mass": [0.05, 1.0]}
    ended = [e for e in events["calibration_finished"] if e.get("error") == "OPERATION_FAILED"]
    assert ended and "interrupted" in ended[0]["message"]
    busy = [e for e in events["calibration_finished"] if e.get("error") == "INCORRECT_STATE"]
    assert busy, events["calibration_finished"]  # the second streak's, refused: busy
    assert sim.list(name="ball")[0].mass == pytest.approx(0.2)  # no apply: untouched


@pytest.mark.parametrize("engine", ["mujoco"])
def test_a_trigger_whose_fit_is_bad_is_refused_and_counts_nothing(sim: Client) -> None:
    sim.spawn(spheres(["a"], [[0, 0, 1]], 0.05, static=True))
    assert sim.compare(["a"], SEEN_WRONG, trigger=TRIGGER).streak == 1
    pose = SEEN_WRONG.tobytes()
    for bad, error in (({"fit": {"crate.friction": [0.1, 1.0]}}, NotFoundError),
                       ({"fit": {"a.friction": [1.0, 0.5]}}, InvalidArgumentError),
                       ({"fit": {"a.mass": [0.1, 1.0]}}, InvalidArgumentError),  # static
                       ({"fit": {}}, InvalidArgumentError),
                       ({"fit": {"a.friction": [0.1, 1.0]}, "max_predictions": 1},
                        InvalidArgumentError),
                       ({"fit": {"a.friction": [0.1, 1.0]}, "after": 1},
                        InvalidArgumentError)):
        with pytest.raises(error):
            sim.call("compare", {"names": ["a"], "poses": pose, "trigger": {
                "threshold": 3.0, "window": 3, "calibrate": bad}})
    assert sim.compare(["a"], SEEN_WRONG, trigger=TRIGGER).streak == 2
