"""The physical-law suite through real daemons: a reduced suite (a few laws, two engines)
whose report must state exactly the numbers of its results.json, deterministic runs, and
clear refusals of unknown laws and engines."""

from __future__ import annotations

import re
from pathlib import Path

from support.cli import run, target_of
from support.daemons import start_daemon

from galton.analysis.laws import LawResults
from galton.analysis.laws_report import number
from galton.client import Client, EmbeddedDaemon
from galton.client.laws import run_laws

REDUCED = "free-fall,rebound,two-spheres,torque-free"
ENGINES = "mujoco,pybullet"
CELL = re.compile(r"(\S+) \((\S+)\) ±(\S+) \*\*(pass|FAIL)\*\*")


def _table_rows(report: str) -> list[list[str]]:
    """The cells of the law table's body rows."""
    lines = [line for line in report.splitlines() if line.startswith("| ")]
    return [[c.strip() for c in line.strip("|").split(" | ")] for line in lines[1:]
            if not line.startswith("| ---")]


def test_the_report_states_the_numbers_of_results_json(
        daemons: dict[str, EmbeddedDaemon], tmp_path: Path) -> None:
    daemon = start_daemon(daemons, "mujoco")
    result = run([*target_of(daemon), "laws", "--engines", ENGINES, "--only", REDUCED,
                  "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    results = LawResults.load(tmp_path / "results.json")
    assert [r.engine for r in results.engines] == ENGINES.split(",")
    rows = _table_rows((tmp_path / "report.md").read_text())
    assert [(r[0], r[1]) for r in rows] == results.rows()
    for law, quantity, _unit, theory, *cells in rows:
        for record, shown in zip(results.engines, cells, strict=True):
            check = results.check(record.engine, law, quantity)
            assert check is not None and check.value is not None
            assert float(theory) == float(number(check.theory))
            value, error, tolerance, verdict = CELL.fullmatch(shown).groups()  # type: ignore[union-attr]
            assert float(value) == float(number(check.value))
            assert float(error) == float(number(check.value - check.theory))
            assert float(tolerance) == float(number(check.tolerance))
            assert verdict == ("pass" if abs(check.value - check.theory) <= check.tolerance
                               else "FAIL")
    assert (tmp_path / "torque_free.png").stat().st_size > 0
    for record in results.engines:  # laws every engine meets by a wide margin
        for law in ("free-fall", "two-spheres"):
            first = next(c for c in record.checks if c.law == law)
            assert first.passed, (record.engine, first)


def test_the_suite_is_deterministic(mujoco_sim: Client) -> None:
    runs = [run_laws(mujoco_sim, ["mujoco"], ["cradle", "torque-free"], seed=3)
            for _ in range(2)]
    checks = [[c.to_dict() for c in r.engines[0].checks] for r in runs]
    assert checks[0] == checks[1]
    assert runs[0].engines[0].series == runs[1].engines[0].series


def test_unknown_laws_and_engines_are_refused_before_any_run(
        daemons: dict[str, EmbeddedDaemon], tmp_path: Path) -> None:
    daemon = start_daemon(daemons, "mujoco")
    bad_law = run([*target_of(daemon), "laws", "--only", "free-fal", "--out", str(tmp_path)])
    assert bad_law.exit_code == 2  # a usage error, found before any daemon is asked
    assert "unknown law(s) free-fal" in bad_law.output and "free-fall" in bad_law.output
    bad_engine = run([*target_of(daemon), "laws", "--engines", "havok", "--out",
                      str(tmp_path)])
    assert bad_engine.exit_code == 1 and "havok" in bad_engine.output
    assert not (tmp_path / "results.json").exists()
