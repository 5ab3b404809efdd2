"""The research probes (research/) and the benchmarks (benchmarks/) as the scripts they are.

They are run, never imported: every script's command line starts (``--help`` imports all it
needs), the probes' own checks pass (research/test_*.py, which pytest runs from research/,
where the probes import each other by name), and a small seeded in-process run goes through
``fidelity_inprocess.py`` into ``seed_spread.py`` as the docs' seed table was made.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = sorted(p for folder in ("research", "benchmarks") for p in (ROOT / folder).glob("*.py")
                 if "argparse" in p.read_text(encoding="utf-8"))
TIMEOUT_S = 240


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=TIMEOUT_S, check=False)


def test_the_scripts_are_where_the_docs_say() -> None:
    names = {p.relative_to(ROOT).as_posix() for p in SCRIPTS}
    assert {"research/exact_lone_ball.py", "research/seed_spread.py", "research/walk_probe.py",
            "research/fidelity_inprocess.py", "research/ab_trials.py",
            "benchmarks/bridge_overhead.py", "benchmarks/physics_cpu.py"} <= names
    assert not (ROOT / "benchmarks" / "fidelity_targets.py").exists()  # galton-client check


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_script_starts(script: Path) -> None:
    result = _run(str(script.relative_to(ROOT)), "--help")
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.startswith("usage:")


def test_the_probes_own_checks_pass() -> None:
    result = _run("-m", "pytest", "research", "-q", "-p", "no:cacheprovider")
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    assert " passed" in result.stdout and "failed" not in result.stdout


def test_an_in_process_run_feeds_the_seed_table(tmp_path: Path) -> None:
    runs = tmp_path / "runs.jsonl"
    for seed in (0, 1):
        made = _run("research/fidelity_inprocess.py", "pybullet", "3", "1", "stream",
                    "--seed", str(seed))
        assert made.returncode == 0, made.stderr[-2000:]
        with runs.open("a", encoding="utf-8") as handle:
            handle.write(made.stdout)
    line = json.loads(runs.read_text().splitlines()[-1])
    assert (line["balls"], line["seed"], line["lost"]) == (3, 1, 0)
    assert sum(line["pooled"]) == 3

    table = _run("research/seed_spread.py", str(runs))
    assert table.returncode == 0, table.stderr[-2000:]
    assert table.stdout.startswith("pybullet stream 3 x 1 {}")
    assert "seed 0: p " in table.stdout and "seed 1: p " in table.stdout
