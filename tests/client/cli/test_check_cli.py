"""``galton-client check RESULTS``: one verdict per cell, exit 0 / 1 / 2, and ``--json``.

The passing runs are the defaults' real bench runs kept in docs/data; the failing ones are
seeded tables of known laws written as results.json.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from support import tilted_law
from support.synthetic_runs import law_trials, write_results
from typer.testing import CliRunner

from galton.analysis import stats
from galton.client.cli.app import app

runner = CliRunner()
BENCH_DEFAULTS = Path(__file__).resolve().parents[3] / "docs" / "data" / "bench-defaults"
RUNS = [str(BENCH_DEFAULTS / "all-at-once"), str(BENCH_DEFAULTS / "stream" / "results.json")]
CELL_LINE = re.compile(r"(\w+)\s+paper\s+(\S+)\s+(\d+) x")


def _lines(output: str) -> dict[tuple[str, str, int], str]:
    """Each cell's line, keyed by engine, release and balls."""
    found = {}
    for line in output.splitlines():
        match = CELL_LINE.match(line)
        if match:
            engine, release, balls = match.groups()
            found[(engine, release, int(balls))] = line
    return found


def test_the_defaults_bench_runs_meet_every_target() -> None:
    result = runner.invoke(app, ["check", *RUNS])
    assert result.exit_code == 0, result.output
    lines = _lines(result.output)
    assert len(lines) == 8 and all(line.endswith("  met") for line in lines.values())
    assert "8 of 8 cells meet every target" in result.output


def test_json_gives_every_cell_and_the_verdict() -> None:
    result = runner.invoke(app, ["check", *RUNS, "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["passed"] is True and len(data["cells"]) == 8
    cell = data["cells"][0]
    assert {"engine", "board", "release", "balls", "trials", "pooled_p", "chi2_median",
            "lost", "unsettled", "passed", "misses"} <= set(cell)
    assert cell["passed"] and cell["misses"] == []


def test_a_missed_target_is_named_and_exits_1(tmp_path: Path) -> None:
    leaky = write_results(tmp_path / "leaky", law_trials(
        "mujoco", "stream", 100, stats.bin_probabilities(), seed=5, lost=2, unsettled=1))
    wide = write_results(tmp_path / "wide", law_trials(
        "pybullet", "all-at-once", 500, tilted_law(0.07), seed=4))
    result = runner.invoke(app, ["check", str(leaky), str(wide / "results.json")])
    assert result.exit_code == 1, result.output
    lines = _lines(result.output)
    assert lines[("mujoco", "stream", 100)].endswith("NOT met: 2 lost; 1 unsettled")
    assert re.search(r"NOT met: pooled p [\d.e-]+ <= 0\.05$",
                     lines[("pybullet", "all-at-once", 500)])
    assert "0 of 2 cells meet every target" in result.output

    as_json = runner.invoke(app, ["check", str(leaky), "--json"])
    assert as_json.exit_code == 1
    assert json.loads(as_json.output)["cells"][0]["misses"] == ["2 lost", "1 unsettled"]


def test_one_failing_cell_fails_the_run(tmp_path: Path) -> None:
    leaky = write_results(tmp_path / "leaky", law_trials(
        "mujoco", "stream", 100, stats.bin_probabilities(), seed=5, lost=1))
    result = runner.invoke(app, ["check", RUNS[0], str(leaky)])
    assert result.exit_code == 1, result.output
    assert "4 of 5 cells meet every target" in result.output


@pytest.mark.parametrize(("name", "content", "reason"), [
    ("missing", None, "cannot read results from"),
    ("broken.json", "{not json", "cannot read results from"),
    ("wrong.json", '{"trials": [{"engine": "mujoco"}]}', "incomplete"),
    ("empty", '{"trials": []}', "the results hold no trial"),
])
def test_unreadable_results_are_refused_with_a_typed_error(
        tmp_path: Path, name: str, content: str | None, reason: str) -> None:
    path = tmp_path / name
    if content is not None:
        path.write_text(content, encoding="utf-8")
    result = runner.invoke(app, ["check", str(path)])
    assert result.exit_code == 2, result.output
    assert result.output.startswith("galton-client: RecordError: ")
    assert reason in result.output and "Traceback" not in result.output


def test_check_needs_a_results_file() -> None:
    result = runner.invoke(app, ["check"])
    assert result.exit_code == 2 and "Missing argument" in result.output
