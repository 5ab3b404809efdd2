"""``galton.analysis.targets``: the fidelity targets recomputed from results.json.

Seeded tables of known laws stand for bench runs: a binomial board meets every target, and
each way of missing one (a wide law, a lost or unsettled ball, trials far from the
binomial, no ball settled) is named in its cell's misses. The report's fidelity check is
built from the same cells.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from support import tilted_law
from support.synthetic_runs import law_trials, write_results

from galton.analysis import stats
from galton.analysis.errors import RecordError
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.summary import summarise
from galton.analysis.targets import (
    MAX_CHI2_MEDIAN,
    MIN_POOLED_P,
    CellVerdict,
    load_trials,
    verdicts,
)
from galton.analysis.verdict import judge

BENCH_DEFAULTS = Path(__file__).resolve().parents[2] / "docs" / "data" / "bench-defaults"


def _by_cell(cells: list[CellVerdict]) -> dict[tuple[str, str], CellVerdict]:
    return {(c.engine, c.release): c for c in cells}


def _lopsided() -> np.ndarray:
    law = np.zeros(12)
    law[:6] = stats.bin_probabilities()[:6] * 2  # every ball falls to the left half
    return law / law.sum()


def test_the_targets_are_the_projects() -> None:
    assert MIN_POOLED_P == 0.05 and MAX_CHI2_MEDIAN == 16.64


def test_a_binomial_board_meets_every_target() -> None:
    (cell,) = verdicts(law_trials("mujoco", "stream", 500, stats.bin_probabilities(), seed=3))
    assert cell.passed and cell.misses == []
    assert cell.line().endswith("met") and "lost 0  unsettled 0" in cell.line()
    assert (cell.balls, cell.trials) == (500, 10)


def test_each_missed_target_is_named() -> None:
    trials = (law_trials("pybullet", "all-at-once", 500, tilted_law(0.07), seed=4)
              + law_trials("mujoco", "stream", 100, stats.bin_probabilities(), seed=5,
                           lost=2, unsettled=1)
              + law_trials("mujoco", "all-at-once", 100, _lopsided(), seed=6))
    cells = _by_cell(verdicts(trials))
    assert not any(c.passed for c in cells.values())
    wide = cells[("pybullet", "all-at-once")]
    assert len(wide.misses) == 1 and re.fullmatch(r"pooled p [\d.e-]+ <= 0\.05", wide.misses[0])
    assert wide.line().endswith("NOT met: " + wide.misses[0])
    assert cells[("mujoco", "stream")].misses == ["2 lost", "1 unsettled"]
    assert any(m.startswith("median chi2") for m in cells[("mujoco", "all-at-once")].misses)


def test_a_cell_where_no_ball_settled_misses_and_says_why() -> None:
    trials = law_trials("mujoco", "stream", 20, stats.bin_probabilities(), seed=7, lost=20)
    (cell,) = verdicts(trials[:1])
    assert cell.pooled_p is None and cell.misses == ["no ball settled", "20 lost"]
    assert "pooled p      -" in cell.line()


def test_a_cells_level_does_not_depend_on_the_other_ball_counts() -> None:
    """Held to p > 0.05 on its own, not Bonferroni-corrected over the counts of the run: a
    100-ball cell at p 0.038 misses alone and beside a 500-ball run, in the report too."""
    alone = law_trials("mujoco", "stream", 100, tilted_law(0.12), seed=37)
    (cell,) = verdicts(alone)
    assert cell.pooled_p is not None and 0.025 < cell.pooled_p <= MIN_POOLED_P
    both = alone + law_trials("mujoco", "stream", 500, stats.bin_probabilities(), seed=3)
    assert [c.passed for c in verdicts(both)] == [False, True]
    for trials in (alone, both):
        (summary,) = summarise(trials)
        assert not judge(summary).checks[0].passed


def test_the_reports_fidelity_check_agrees_with_the_cells() -> None:
    trials = (law_trials("mujoco", "stream", 100, stats.bin_probabilities(), seed=5,
                         lost=2, unsettled=1)
              + law_trials("mujoco", "stream", 500, stats.bin_probabilities(), seed=3))
    (summary,) = summarise(trials)
    fidelity = next(c for c in judge(summary).checks if c.name == "fidelity")
    cells = verdicts(trials)
    assert [c.passed for c in cells] == [False, True]
    assert not fidelity.passed and fidelity.detail == "targets missed at 100 balls: 2 lost; " \
        "1 unsettled"
    (fair,) = summarise(law_trials("mujoco", "stream", 500, stats.bin_probabilities(), seed=3))
    assert next(c for c in judge(fair).checks if c.name == "fidelity").passed


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
def test_a_real_bench_run_is_recomputed_as_its_report_gave_it(release: str) -> None:
    """The defaults' bench runs kept in docs/data: from results.json alone, the targets find
    the median chi2 and pooled p that the bench wrote in its report."""
    folder = BENCH_DEFAULTS / release
    reported = _report_rows(folder / "report.md")
    cells = verdicts(load_trials([folder]))
    assert {(c.engine, c.balls) for c in cells} == set(reported) and len(reported) == 4
    for cell in cells:
        assert cell.release == release and cell.board == "paper"
        chi2, p = reported[(cell.engine, cell.balls)]
        assert cell.chi2_median == pytest.approx(chi2, rel=1e-3)  # four figures
        assert cell.pooled_p is not None and round(cell.pooled_p, 3) == p


def test_unreadable_or_empty_results_are_refused_with_the_reason(tmp_path: Path) -> None:
    with pytest.raises(RecordError, match="cannot read results from"):
        load_trials([tmp_path / "missing"])
    empty = write_results(tmp_path / "empty", [])
    with pytest.raises(RecordError, match="the results hold no trial"):
        load_trials([empty])


def test_files_and_folders_are_pooled(tmp_path: Path) -> None:
    first = law_trials("mujoco", "stream", 100, stats.bin_probabilities(), seed=1)
    second = law_trials("pybullet", "stream", 100, stats.bin_probabilities(), seed=2)
    a = write_results(tmp_path / "a", first)
    b = write_results(tmp_path / "b", second)
    loaded: list[TrialRecord] = load_trials([a, b / "results.json"])
    assert loaded == ExperimentResults.from_json(a / "results.json").trials + second


def test_every_name_galton_analysis_exports_resolves() -> None:
    """The package imports its names on first use: each must exist where it says."""
    import galton.analysis as analysis

    for name in analysis.__all__:
        assert getattr(analysis, name) is not None, name
