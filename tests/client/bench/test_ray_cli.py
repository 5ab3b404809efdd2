"""Issue 52's "done when", as a user types it (slow: each command starts its own daemons,
and --ray local its own Ray instance, ~13 s on 2 cores): `galton-client bench --ray local
--engines mujoco --balls 30 --repetitions 4` gives the plain run's bins trial for trial and
records the executor with its nodes; `sweep --ray local` runs its grid on Ray too.
Run with ``python -m pytest -m slow tests/client/bench/test_ray_cli.py``."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import pytest
from support.cli import CONSOLE_COMMAND

pytestmark = pytest.mark.slow

ISSUE_PLAN = ["--engines", "mujoco", "--balls", "30", "--repetitions", "4"]
RUN_TIMEOUT_S = 600


def bench(args: list[str], out: Path) -> dict[str, Any]:
    """Run ``galton-client bench`` as a user would; its results.json."""
    done = subprocess.run([CONSOLE_COMMAND, "bench", *args, "--out", str(out), "--json"],
                          capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)
    assert done.returncode == 0, done.stderr
    said = json.loads(done.stdout)
    saved: dict[str, Any] = json.loads((out / "results.json").read_text())
    assert said["executor"] == saved["executor"]
    return saved


def test_bench_ray_local_gives_the_plain_runs_bins_trial_for_trial(tmp_path: Path) -> None:
    on_ray = bench(["--ray", "local", *ISSUE_PLAN], tmp_path / "ray")
    plain = bench(ISSUE_PLAN, tmp_path / "plain")
    assert [(t["repetition"], t["counts"]) for t in on_ray["trials"]] == [
        (t["repetition"], t["counts"]) for t in plain["trials"]]
    assert plain["executor"] == {"kind": "local"}
    executor = on_ray["executor"]
    assert executor["kind"] == "ray" and executor["address"] == "local"
    assert executor["nodes"] == 1 and executor["actors"] >= 1 and executor["retried"] == []
    assert {t["daemon"] for t in on_ray["trials"]} == set(on_ray["hosts"])


def test_sweep_ray_local_runs_the_grid_on_actors(tmp_path: Path) -> None:
    out = tmp_path / "sweep"
    done = subprocess.run(
        [CONSOLE_COMMAND, "sweep", "--ray", "local", "--ray-actors", "2", "--param",
         "default_friction=0.3,0.6", "--engines", "pybullet", "--board", "small", "--balls",
         "5", "--repetitions", "2", "--max-sim-time", "5", "--out", str(out)],
        capture_output=True, text=True, timeout=RUN_TIMEOUT_S, check=False)
    assert done.returncode == 0, done.stderr
    assert "Ran on Ray (local): 2 actor(s) on 1 node(s); no trial(s) retried" in done.stdout
    saved = json.loads((out / "results.json").read_text())
    assert saved["executor"]["kind"] == "ray" and len(saved["trials"]) == 4
    assert {t["daemon"] for t in saved["trials"]} <= {"ray-1", "ray-2"}
