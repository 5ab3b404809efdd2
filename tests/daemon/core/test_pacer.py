"""The pacer keeps a playing world's clock: a stall of the physics thread shorter than
MAX_LAG_S is caught up step for step; a longer one is forgiven once, and the clock
re-anchors where the world is (issue 35, item 9: 20 rendering clients stall it ~1 s)."""

from __future__ import annotations

import pytest

from galton.daemon.core.monitor import Pacer

DT = 0.001


def _playing(rtf: float = 1.0) -> Pacer:
    pacer = Pacer()
    pacer.anchor(wall=100.0, sim=5.0, rtf=rtf)
    return pacer


def test_a_stall_of_a_second_is_caught_up_step_for_step() -> None:
    pacer = _playing()
    assert pacer.steps_due(100.0 + 1.0, 5.0, DT) == pytest.approx(1000, abs=1)
    assert pacer.steps_due(100.0 + 1.0, 6.0, DT) == 0  # caught up: nothing owed


def test_a_stall_longer_than_the_lag_bound_is_forgiven_once() -> None:
    pacer = _playing()
    stalled = Pacer.MAX_LAG_S + 0.5
    assert pacer.steps_due(100.0 + stalled, 5.0, DT) == 1  # gives the backlog up
    assert pacer.steps_due(100.0 + stalled + 0.01, 5.0, DT) == pytest.approx(10, abs=1)


def test_the_bound_scales_with_the_target_rtf() -> None:
    """At RTF 0.5 a 1.5 s stall owes 0.75 s of sim time: caught up, not forgiven."""
    pacer = _playing(rtf=0.5)
    assert pacer.steps_due(100.0 + 1.5, 5.0, DT) == pytest.approx(750, abs=1)


def test_rtf_zero_runs_as_fast_as_it_can() -> None:
    assert _playing(rtf=0.0).steps_due(100.0 + 1.0, 5.0, DT) == -1
