"""The engine checker: every check passes on every engine, and engines that break the
interface fail the check that names their breach, with what was expected and seen."""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Sequence

import numpy as np
import pytest

from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.engines.base import FEATURE_LOAD_MODEL
from galton.daemon.engines.check import (
    ENGINE_CHECKS,
    EngineCheckError,
    check_engine,
    run_check,
)
from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.protocol import Capabilities, InvalidArgumentError


@pytest.mark.parametrize(("engine", "check"), [
    pytest.param(engine, check.name, id=f"{engine}-{check.name}")
    for engine in ENGINE_CLASSES for check in ENGINE_CHECKS])
def test_every_engine_passes_every_check(engine: str, check: str) -> None:
    result = run_check(engine, check)
    assert result.outcome == "passed", result.message


def test_check_engine_reports_every_check() -> None:
    report = check_engine(MujocoEngine)
    assert report.ok and report.engine == "mujoco"
    assert [r.name for r in report.results] == [c.name for c in ENGINE_CHECKS]
    assert report.summary().splitlines()[0] == f"mujoco: {len(ENGINE_CHECKS)} passed, " \
        "0 failed, 0 skipped"


def test_each_check_has_a_name_and_says_what_it_guarantees() -> None:
    names = [c.name for c in ENGINE_CHECKS]
    assert len(set(names)) == len(names)
    assert all(c.guarantee.endswith(".") and len(c.guarantee) > 40 for c in ENGINE_CHECKS)


class ForgetfulEngine(MujocoEngine):
    """Breaks "None leaves that part as it is": a pose set alone stops the body."""

    def set_states(self, names: Sequence[str], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
        if poses is not None and twists is None:
            twists = np.zeros((len(names), 6))
        super().set_states(names, poses, twists)


def test_a_broken_engine_fails_the_check_it_breaks_with_a_clear_message() -> None:
    with pytest.raises(EngineCheckError) as caught:
        check_engine(ForgetfulEngine)
    report = caught.value.report
    assert [r.name for r in report.failures] == ["state-round-trip"]
    message = str(caught.value)
    assert f"the mujoco engine failed 1 of {len(ENGINE_CHECKS)} checks" in message
    assert ("state-round-trip: twists after a pose set alone: expected 3.0 within 1e-09 at "
            "[1, 4]; saw 0.0 (off by 3)") in message


class BlindEngine(PybulletEngine):
    """Never sees a divergence, and crashes when asked for properties."""

    def state_within(self, max_position: float, max_speed: float) -> bool:
        return True

    def properties(self, names: Sequence[str]) -> np.ndarray:
        raise ZeroDivisionError("no properties today")


def test_an_engines_crash_fails_its_check_and_the_run_goes_on() -> None:
    with pytest.raises(EngineCheckError) as caught:
        check_engine(BlindEngine)
    failures = {r.name: r.message for r in caught.value.report.failures}
    assert failures["state-within"] == (
        "state_within after a NaN speed: expected False; saw True")
    assert failures["properties"] == "raised ZeroDivisionError: no properties today"
    assert len(caught.value.report.results) == len(ENGINE_CHECKS)


class NoModels(PybulletEngine):
    """An engine that cannot load models, and says so."""

    def capabilities(self) -> Capabilities:
        caps = super().capabilities()
        caps.features = tuple(f for f in caps.features if f != FEATURE_LOAD_MODEL)
        return caps


def test_checks_of_features_an_engine_does_not_list_are_skipped() -> None:
    report = check_engine(NoModels)
    skipped = [r.name for r in report.results if r.outcome == "skipped"]
    assert report.ok and skipped == ["load-model", "bad-models"]
    assert all("'load_model' feature" in r.message for r in report.results
               if r.outcome == "skipped")


def test_params_are_set_on_every_engine_a_check_makes() -> None:
    assert run_check("pybullet", "determinism", params={"timestep": 1 / 480}).outcome == \
        "passed"
    result = run_check("mujoco", "timestep", params={"nonsense": 1})
    assert result.outcome == "failed" and "unknown parameter 'nonsense'" in result.message
    with pytest.raises(InvalidArgumentError, match="unknown parameter 'nonsense'"):
        check_engine("mujoco", params={"nonsense": 1})


def test_unknown_engines_and_checks_are_refused_by_name() -> None:
    with pytest.raises(InvalidArgumentError, match="did you mean 'mujoco'"):
        check_engine("mujuco")
    with pytest.raises(InvalidArgumentError, match="did you mean 'determinism'"):
        run_check("mujoco", "determinsm")


def test_the_checker_imports_no_engine() -> None:
    """It works on any class implementing the interface: importing it loads no engine."""
    engines = ("mujoco", "pybullet", "dart", "ode")
    probe = ("import sys, galton.daemon.engines.check; "
             f"engines = {engines!r}; "
             "print(sorted(m for m in sys.modules if m.split('.')[0] in "
             "(*engines, 'dartpy') or m.startswith(tuple("
             "f'galton.daemon.engines.{e}' for e in engines))))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         check=True, timeout=60)
    assert out.stdout.strip() == "[]"
