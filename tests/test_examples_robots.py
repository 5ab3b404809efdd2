"""The robot examples run, short: in this process against the session's daemons (both
engines), and once each as a program with its own embedded daemon, exiting 0."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

from galton.client import EmbeddedDaemon

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"
PROGRAM_TIMEOUT_S = 120.0


def load_example(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # its dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def connect(daemon: EmbeddedDaemon) -> list[str]:
    return ["--connect", daemon.endpoint, "--instance", daemon.instance]


def test_mirror_robot_streams_and_reads_the_flange(daemon: EmbeddedDaemon) -> None:
    run = load_example("mirror_robot").main([*connect(daemon), "--seconds", "0.3"])
    assert run.cycles == 30 and 0 < run.p50_ms <= run.p99_ms
    assert np.all(np.isfinite(run.flange))
    travelled = np.linalg.norm(np.diff(run.flange, axis=0), axis=1)
    assert np.all(travelled > 0)  # every sample moved the flange


def test_pd_arm_reaches_its_target(daemon: EmbeddedDaemon) -> None:
    example = load_example("pd_arm")
    final = example.main([*connect(daemon), "--seconds", "1.0"])
    assert final.sim_time >= 1.0
    # What is left is gravity's sag over kp: about 0.02 rad at the shoulder.
    np.testing.assert_allclose(final.positions, example.TARGET, atol=0.03)


def test_imagine_plans_picks_the_best_and_lands_where_it_imagined(
        daemon: EmbeddedDaemon) -> None:
    choice = load_example("imagine_plans").main([*connect(daemon), "--plans", "4",
                                                 "--horizon", "0.3"])
    assert len(choice.scores) == 4 and len(set(choice.scores.tolist())) == 4
    assert choice.best == int(np.argmin(choice.scores))
    assert choice.live == choice.imagined  # bit for bit: the same physics, not a model


def test_the_robot_examples_run_as_programs() -> None:
    for name, args in (("mirror_robot", ["--seconds", "0.2"]), ("pd_arm", ["--seconds", "0.5"])):
        done = subprocess.run([sys.executable, str(EXAMPLES / f"{name}.py"), *args],
                              capture_output=True, text=True, timeout=PROGRAM_TIMEOUT_S,
                              check=False)
        assert done.returncode == 0, done.stdout + done.stderr
        assert "mujoco:" in done.stdout
