"""Absurd numbers get INVALID_ARGUMENT, long work can be stopped, and replies are bounded
(issue 35: the wrong codes, items 5 and 6). On both engines, over Zenoh."""

from __future__ import annotations

import math
import queue
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from support import companion, snapshot

from galton.client import Client, plane, spheres
from galton.protocol import (
    IncorrectStateError,
    InvalidArgumentError,
    NotFoundError,
    OperationFailedError,
    ResourceLimitError,
)

WAIT_S = 30.0
ABSURD = [
    ("predict", {"horizon": 5e-324}),
    ("predict", {"horizon": 1e308}),
    ("apply_wrench", {"names": ["ball"], "wrenches": np.zeros(6).tobytes(),
                      "duration": 1e308}),
    ("render", {"cameras": [{"eye": [1, 1, 1], "target": [0, 0, 0], "near": 1e-300,
                             "width": 8, "height": 8}]}),
]


@pytest.mark.parametrize(("op", "args"), ABSURD, ids=[f"{op}-{i}" for i, (op, _) in
                                                      enumerate(ABSURD)])
def test_an_absurd_number_is_invalid_argument_and_changes_nothing(
        sim: Client, op: str, args: dict[str, Any]) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    before = snapshot(sim)
    with pytest.raises(InvalidArgumentError):
        sim.call(op, args)
    snapshot(sim).assert_same(before)
    assert sim.step(1).step == 1


def test_every_sample_fits_a_prediction_shorter_than_its_period(sim: Client) -> None:
    """An ``every`` past the horizon (1e308 s overflowed once) samples its start and end."""
    sim.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05))
    result = sim.call("predict", {"horizon": 0.01, "every": 1e308, "read": ["ball"]})
    assert result["steps"] == math.ceil(0.01 / sim.status().timestep - 1e-9)
    assert len(result["times"]) == 2 * 8


def test_a_prediction_whose_reply_is_too_big_is_refused_up_front(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05))
    with pytest.raises(ResourceLimitError, match="max_reply_bytes") as refused:
        sim.call("predict", {"horizon": 1e4, "read": ["ball"]})
    assert refused.value.details["limit"] == "max_reply_bytes"
    assert sim.step(1).step == 1  # nothing holds the step slot


def _in_background(call: Callable[[], Any]) -> queue.Queue[Any]:
    out: queue.Queue[Any] = queue.Queue()

    def run() -> None:
        try:
            out.put(call())
        except Exception as exc:
            out.put(exc)
    threading.Thread(target=run, daemon=True).start()
    return out


def _predicting(sim: Client) -> bool:
    """Whether a prediction holds the daemon's step slot (a probe that starts nothing:
    with the slot free, an unknown slot is NOT_FOUND)."""
    try:
        sim.call("predict", {"horizon": 1.0, "slot": "no-such-slot"})
    except IncorrectStateError:
        return True
    except NotFoundError:
        return False
    raise AssertionError("the probe started a prediction")


@pytest.mark.parametrize("ender", ["pause", "stop", "reset"])
def test_a_long_prediction_ends_at_pause_stop_or_reset(sim: Client, ender: str) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    other = companion(sim)
    try:
        answer = _in_background(lambda: other.call(  # a sample every 10 s: a small reply
            "predict", {"horizon": 1e4, "every": 10.0}, timeout=60))
        while not _predicting(sim):
            assert answer.empty(), f"the prediction ended early: {answer.get()}"
        sim.call(ender)
        ended = answer.get(timeout=WAIT_S)
        assert isinstance(ended, OperationFailedError) and "interrupted" in ended.message
        assert not _predicting(sim)
        assert sim.step(2).step >= 2
    finally:
        other.close()
