"""examples/learn_from_surprise.py runs against the session's daemon (MuJoCo; PyBullet too
with -m slow), its result held to what its docstring states: the scores low, then high
once reality's friction changes, low again after the calibration it triggered (and with
--auto, the calibration the daemon started itself)."""

from __future__ import annotations

import pytest
from support.worlds import clean
from test_examples_robots import connect, load_example

from galton.client import Client, EmbeddedDaemon


def learns(sim: Client, daemon: EmbeddedDaemon) -> None:
    example = load_example("learn_from_surprise")
    with clean(sim):
        run = example.main([*connect(daemon), "--seed", "3"])
    first, changed, after = run.peaks
    assert first < example.THRESHOLD and after < example.THRESHOLD
    assert changed > 3 * example.THRESHOLD
    assert run.fitted == pytest.approx(example.REAL_FRICTION, rel=0.1)
    assert 0 < run.predictions <= 100


@pytest.mark.parametrize("engine", ["mujoco"])
def test_learn_from_surprise(sim: Client, daemon: EmbeddedDaemon) -> None:
    learns(sim, daemon)


@pytest.mark.parametrize("engine", ["mujoco"])
def test_the_daemon_calibrates_on_surprise_by_itself(sim: Client,
                                                      daemon: EmbeddedDaemon) -> None:
    """--auto: the trigger's calibrate starts the fit in the daemon (no client calibrate),
    over the streak's 8 observations: it recovers reality's friction within 10 % and
    applies it, and the next episode's scores are low again."""
    example = load_example("learn_from_surprise")
    with clean(sim):
        run = example.main([*connect(daemon), "--seed", "3", "--auto"])
    first, changed, after = run.peaks
    assert first < example.THRESHOLD and after < example.THRESHOLD
    assert changed > 3 * example.THRESHOLD
    assert run.fitted == pytest.approx(example.REAL_FRICTION, rel=0.1)
    assert 0 < run.predictions <= example.AUTO_PREDICTIONS


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["pybullet"])
def test_learn_from_surprise_on_pybullet(sim: Client, daemon: EmbeddedDaemon) -> None:
    learns(sim, daemon)
