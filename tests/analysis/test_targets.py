"""``benchmarks/fidelity_targets.py``: the fidelity targets recomputed from results.json.

Seeded tables of known laws stand for bench runs: a binomial board meets every target, and
each way of missing one (a wide law, a lost or unsettled ball, trials far from the
binomial) is named on its cell's line and makes the script exit 1.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from support import import_benchmark, tilted_law

from galton.analysis import stats
from galton.analysis.records import ExperimentResults, TrialRecord


@pytest.fixture(scope="module")
def targets():
    return import_benchmark("fidelity_targets")


def _trials(engine: str, release: str, balls: int, law: np.ndarray, seed: int,
            lost: int = 0, unsettled: int = 0) -> list[TrialRecord]:
    """Ten repetitions of ``balls`` drawn from ``law``; repetition 0 loses and strands balls."""
    rng = np.random.default_rng(seed)
    trials = []
    for repetition in range(10):
        missing = (lost + unsettled) if repetition == 0 else 0
        counts = rng.multinomial(balls - missing, law).tolist()
        trials.append(TrialRecord(
            engine=engine, engine_version="x", board="paper", balls=balls,
            repetition=repetition, seed=0, release=release, counts=counts,
            settled=balls - missing, lost=lost if repetition == 0 else 0,
            lost_by_reason={"below_floor": lost if repetition == 0 else 0},
            unsettled=unsettled if repetition == 0 else 0))
    return trials


def _write(tmp_path: Path, name: str, trials: list[TrialRecord]) -> Path:
    folder = tmp_path / name
    folder.mkdir()
    ExperimentResults(trials=trials).to_json(folder / "results.json")
    return folder


def _lines(output: str) -> dict[tuple[str, str], str]:
    """Each cell's line, keyed by engine and release."""
    found = {}
    for line in output.splitlines():
        match = re.match(r"(\w+)\s+paper\s+(\S+)\s+\d+ x", line)
        if match:
            found[match.groups()] = line
    return found


def test_a_binomial_board_meets_every_target(targets, tmp_path: Path, capsys) -> None:
    folder = _write(tmp_path, "fair", _trials("mujoco", "stream", 500,
                                              stats.bin_probabilities(), seed=3))
    assert targets.main([str(folder)]) == 0
    out = capsys.readouterr().out
    line = _lines(out)[("mujoco", "stream")]
    assert line.endswith("met") and "lost 0  unsettled 0" in line
    assert "1 of 1 cells meet every target" in out


def test_each_missed_target_is_named_and_fails_the_run(targets, tmp_path: Path,
                                                       capsys) -> None:
    wide = _write(tmp_path, "wide", _trials("pybullet", "all-at-once", 500,
                                            tilted_law(0.07), seed=4))
    leaky = _write(tmp_path, "leaky", _trials("mujoco", "stream", 100,
                                              stats.bin_probabilities(), seed=5,
                                              lost=2, unsettled=1))
    lopsided = np.zeros(12)
    lopsided[:6] = stats.bin_probabilities()[:6] * 2  # every ball falls to the left half
    skewed = _write(tmp_path, "skewed", _trials("mujoco", "all-at-once", 100,
                                                lopsided / lopsided.sum(), seed=6))
    assert targets.main([str(wide), str(leaky / "results.json"), str(skewed)]) == 1
    out = capsys.readouterr().out
    lines = _lines(out)
    assert re.search(r"NOT met: pooled p [\d.e-]+ <= 0\.05$", lines[("pybullet", "all-at-once")])
    assert lines[("mujoco", "stream")].endswith("NOT met: 2 lost; 1 unsettled")
    assert "median chi2" in lines[("mujoco", "all-at-once")].split("NOT met:")[1]
    assert "0 of 3 cells meet every target" in out


def _report_rows(report: Path) -> dict[tuple[str, int], tuple[float, float]]:
    """(median chi2 per trial, pooled MC p) of each engine and ball count in a bench report."""
    rows, engine = {}, ""
    for line in report.read_text().splitlines():
        if line.startswith("### "):
            engine = line[4:].strip()
        cells = [c.strip() for c in line.strip("|").split("|")]
        if engine and len(cells) > 6 and cells[0].isdigit():
            rows[(engine, int(cells[0]))] = (float(cells[2]), float(cells[6]))
    return rows


@pytest.mark.parametrize("release", ["all-at-once", "stream"])
def test_a_real_bench_run_is_recomputed_as_its_report_gave_it(targets, release: str) -> None:
    """The defaults' bench runs kept in docs/data: from results.json alone, the script finds
    the median chi2 and pooled p that the bench wrote in its report."""
    folder = Path(__file__).resolve().parents[1] / "docs" / "data" / "bench-defaults" / release
    reported = _report_rows(folder / "report.md")
    cells = targets.verdicts(targets.load_trials([str(folder)]))
    assert {(c.engine, c.balls) for c in cells} == set(reported) and len(reported) == 4
    for cell in cells:
        assert cell.release == release and cell.board == "paper"
        chi2, p = reported[(cell.engine, cell.balls)]
        assert cell.chi2_median == pytest.approx(chi2, rel=1e-3)  # four figures
        assert round(cell.pooled_p, 3) == p


def test_unreadable_or_empty_results_are_refused_with_the_reason(targets, tmp_path: Path,
                                                                 capsys) -> None:
    with pytest.raises(SystemExit) as exited:
        targets.main([str(tmp_path / "missing")])
    assert exited.value.code == 2
    assert "cannot read results from" in capsys.readouterr().err
    empty = _write(tmp_path, "empty", [])
    with pytest.raises(SystemExit):
        targets.main([str(empty)])
    assert "the results hold no trial" in capsys.readouterr().err
