"""compare's surprise trigger over a real daemon: comparisons in a row above the threshold
are counted per world, the one that makes the streak its window suggests a calibration
(in its reply and in a `calibration_suggested` event) once per streak, an unsurprising
comparison ends the streak, and a bad trigger is refused without counting."""

from __future__ import annotations

import threading
from typing import Any

import numpy as np
import pytest

from galton.client import Client, spheres
from galton.protocol import InvalidArgumentError

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
