"""The ahead-of-reality examples run, each with its measured result held to what its
docstring states: in this process against the session's daemons (both engines, seeded),
and once each as a program with its own embedded daemon, exiting 0."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator

import pytest
from support.worlds import clean
from test_examples_robots import EXAMPLES, PROGRAM_TIMEOUT_S, connect, load_example

from galton.client import Client, EmbeddedDaemon

AHEAD = ("normality", "gravity_filter", "occlusion")


@pytest.fixture
def target(sim: Client, daemon: EmbeddedDaemon) -> Iterator[list[str]]:
    """The session's daemon, with no side world or slot before or after."""
    with clean(sim):
        yield connect(daemon)


def test_normality_the_score_stays_low_then_spikes(target: list[str]) -> None:
    example = load_example("normality")
    run = example.main([*target, "--seed", "3"])
    assert run.before.max() < example.THRESHOLD
    assert 0.5 < run.before.mean() < 1.5  # about 1 at the camera's noise
    assert run.scores[run.push_at] > 10 * example.THRESHOLD / 3
    assert run.scores[run.push_at + 1:].max() < example.THRESHOLD  # corrected, normal again


def test_gravity_filter_settles_closer_to_the_truth(target: list[str]) -> None:
    run = load_example("gravity_filter").main([*target, "--seed", "5"])
    assert run.perceived.height > 0.005 and run.perceived.angle > 0.01
    # MuJoCo's sleep (the daemon's, 5 mm/s) freezes a box within about 0.2 mm of its rest
    # with MuJoCo's own impedance: 58x on seed 5 (831x with sleeping off)
    assert run.factor("height") >= 50
    assert run.factor("angle") >= 5
    assert run.factor("position") > 1


def test_occlusion_the_prediction_holds_the_hidden_ball(target: list[str]) -> None:
    run = load_example("occlusion").main([*target, "--seed", "11"])
    assert run.hidden_cycles >= 10
    assert run.max_error < 0.01
    assert run.predicted_out == run.out > 0


def test_the_ahead_examples_run_as_programs() -> None:
    for name in AHEAD:
        done = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py")],
                              capture_output=True, text=True, timeout=PROGRAM_TIMEOUT_S,
                              check=False)
        assert done.returncode == 0, done.stdout + done.stderr
        assert "mujoco:" in done.stdout
