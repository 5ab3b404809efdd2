"""Records, summaries, verdicts, the report, the CSV and the plots, on synthetic trials."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from galton.analysis import stats
from galton.analysis.errors import RecordError
from galton.analysis.outputs import write_outputs
from galton.analysis.plots import plot_all
from galton.analysis.published import PUBLISHED_LABEL, PUBLISHED_TABLE2
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.report import render_report, write_csv
from galton.analysis.summary import score_trial, summarise
from galton.analysis.verdict import MAX_LOST_PERCENT, judge, judge_all

SEED = 11
DRAWS = 500
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# A board far narrower than the binomial: most balls in the four central bins.
NARROW = np.array([0, 0, 0, 1, 10, 39, 39, 10, 1, 0, 0, 0]) / 100


def make_trial(engine: str, balls: int, repetition: int, rng: np.random.Generator, *,
               probabilities: np.ndarray | None = None, lost: int = 0, rtf: float = 2.0,
               cpu: float | None = 80.0, rss: int = 150_000_000) -> TrialRecord:
    """A trial whose settled balls land as a multinomial draw from ``probabilities``."""
    p = stats.bin_probabilities() if probabilities is None else probabilities
    counts = rng.multinomial(balls - lost, p).tolist()
    return TrialRecord(
        engine=engine, engine_version="1.0", board="paper", balls=balls,
        repetition=repetition, seed=1000 + repetition, release="all-at-once", counts=counts,
        settled=balls - lost, lost=lost, lost_by_reason={"tunnelled": lost},
        sim_time=10.0, wall_time=10.0 / rtf, rtf=rtf, cpu_percent_mean=cpu,
        peak_rss_bytes=rss + balls * 1000, settings={"timestep": 0.002},
        config={"rows": 11, "balls": balls},
    )


@pytest.fixture
def results() -> ExperimentResults:
    rng = np.random.default_rng(SEED)
    trials = [make_trial("mujoco", n, r, rng, rtf=3.0 - 0.001 * n) for n in (100, 250)
              for r in range(3)]
    trials += [make_trial("pybullet", n, r, rng, probabilities=NARROW, rtf=0.5, lost=r,
                          cpu=None) for n in (100, 250) for r in range(3)]
    return ExperimentResults(trials=trials, date="2024-06-01T00:00:00Z", host="test-host",
                             versions={"python": "3.11"}, command="galton-client bench")


def test_results_json_round_trip(results: ExperimentResults, tmp_path: Path) -> None:
    results.trials[0] = score_trial(results.trials[0], draws=DRAWS)
    path = results.to_json(tmp_path / "results.json")
    assert ExperimentResults.from_json(path) == results
    data = json.loads(path.read_text())
    assert data["trials"][1]["chi2"] is None and data["trials"][0]["chi2"] > 0


def test_records_are_json_safe_and_checked() -> None:
    rng = np.random.default_rng(SEED)
    trial = make_trial("mujoco", 25, 0, rng)
    trial.rtf = float(np.float64("inf"))
    trial.counts = list(np.asarray(trial.counts, dtype=np.int64))
    assert json.dumps(trial.to_dict(), allow_nan=False)
    assert trial.to_dict()["rtf"] is None
    data = trial.to_dict()
    with pytest.raises(RecordError, match="bins hold"):
        TrialRecord.from_dict({**data, "settled": data["settled"] + 1})
    with pytest.raises(RecordError, match="unknown fields"):
        TrialRecord.from_dict({**data, "colour": "red"})
    with pytest.raises(RecordError, match="release"):
        TrialRecord.from_dict({**data, "release": "drip"})
    with pytest.raises(RecordError, match="incomplete"):
        TrialRecord.from_dict({k: v for k, v in data.items() if k != "counts"})


def test_score_trial_with_no_settled_ball_leaves_scores_empty() -> None:
    trial = make_trial("mujoco", 10, 0, np.random.default_rng(SEED), lost=10)
    assert score_trial(trial).chi2 is None
    assert trial.lost_percent == 100.0


def test_summary_numbers(results: ExperimentResults) -> None:
    mujoco, pybullet = summarise(results.trials, draws=DRAWS)
    assert (mujoco.label, pybullet.label) == ("mujoco", "pybullet")
    group = mujoco.groups[0]
    trials = [t for t in results.trials if t.engine == "mujoco" and t.balls == 100]
    chi2s = [stats.chi2_statistic(t.counts) for t in trials]
    assert group.chi2_median == pytest.approx(np.median(chi2s))
    assert group.chi2_mean == pytest.approx(np.mean(chi2s))
    pooled_counts = np.sum([t.counts for t in trials], axis=0)
    assert group.pooled is not None
    assert group.pooled.chi2 == pytest.approx(stats.chi2_statistic(pooled_counts))
    assert group.pooled.effect_size == pytest.approx(math.sqrt(
        max(0.0, group.pooled.chi2 - 11) / pooled_counts.sum()))
    assert group.pooled.detectable_effect == pytest.approx(
        stats.detectable_effect(int(pooled_counts.sum())))
    assert group.rtf_min == group.rtf_max == pytest.approx(2.9)
    assert mujoco.overall.peak_rss_bytes == 150_250_000
    assert pybullet.overall.lost == 6
    assert pybullet.overall.lost_percent_pooled == pytest.approx(100 * 6 / 1050)
    assert pybullet.overall.cpu_percent_mean is None


def test_summary_is_reproducible(results: ExperimentResults) -> None:
    assert summarise(results.trials, draws=DRAWS) == summarise(results.trials, draws=DRAWS)


def test_verdicts(results: ExperimentResults) -> None:
    mujoco, pybullet = judge_all(summarise(results.trials, draws=DRAWS))
    assert mujoco.suitable and mujoco.verdict == "suitable" and not mujoco.reasons
    assert pybullet.verdict == "not suitable"
    failed = {c.name for c in pybullet.checks if not c.passed}
    assert failed == {"fidelity", "loss", "speed", "footprint"}
    assert any("not measured" in reason for reason in pybullet.reasons)


def test_loss_threshold_is_inclusive() -> None:
    rng = np.random.default_rng(SEED)
    balls = int(100 / MAX_LOST_PERCENT)
    trials = [make_trial("mujoco", balls, 0, rng, lost=1)]
    (summary,) = summarise(trials, draws=DRAWS)
    assert next(c for c in judge(summary).checks if c.name == "loss").passed


def test_report_has_our_rows_and_the_published_ones(results: ExperimentResults) -> None:
    summaries = summarise(results.trials, draws=DRAWS)
    text = render_report(results, summaries, judge_all(summaries), ["rtf_vs_balls.png"],
                         draws=DRAWS)
    for row in PUBLISHED_TABLE2:
        line = next(x for x in text.splitlines() if x.startswith(f"| {row.simulator} |"))
        assert PUBLISHED_LABEL in line and f"{row.chi2:.2f}" in line
    assert "| mujoco | this project |" in text and "median per trial" in text
    assert "19.675" in text and "19.68" in text
    assert "effect w [detectable]" in text
    w = summaries[0].groups[0].pooled.effect_size
    assert f"| {w:.3f} [" in text
    assert "**not suitable**" in text and "500 MB" in text
    assert "[rtf_vs_balls.png](rtf_vs_balls.png)" in text


def test_csv_has_one_row_per_trial(results: ExperimentResults, tmp_path: Path) -> None:
    path = write_csv(results.trials, tmp_path / "results.csv")
    with path.open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == len(results.trials)
    assert [int(rows[0][f"bin_{i}"]) for i in range(12)] == results.trials[0].counts
    assert rows[0]["chi2"] == ""


def test_plots_are_png_and_no_figure_leaks(results: ExperimentResults, tmp_path: Path) -> None:
    import matplotlib.pyplot as plt

    paths = plot_all(results.trials, tmp_path, draws=DRAWS)
    curves = {"rtf_vs_balls.png", "resources_vs_balls.png"} if len(
        {t.balls for t in results.trials}) > 1 else set()
    assert {p.name for p in paths} == {"histogram_mujoco.png", "histogram_pybullet.png", *curves}
    for path in paths:
        assert path.read_bytes().startswith(PNG_SIGNATURE) and path.stat().st_size > 1000
    assert plt.get_fignums() == []


def test_a_single_ball_count_draws_no_curve_and_says_why(results: ExperimentResults,
                                                          tmp_path: Path) -> None:
    """One ball count gives one point per engine: no RTF or footprint plot (issue 33)."""
    single = [t for t in results.trials if t.balls == results.trials[0].balls]
    names = {p.name for p in plot_all(single, tmp_path, draws=DRAWS)}
    assert names == {"histogram_mujoco.png", "histogram_pybullet.png"}
    one = ExperimentResults(trials=single, date="", host="", versions={}, command="")
    text = render_report(one, summarise(single, DRAWS), [], sorted(names), DRAWS)
    assert "drawn for two ball counts at least" in text


def test_write_outputs_rerenders_identically(results: ExperimentResults, tmp_path: Path) -> None:
    results.trials.append(make_trial("mujoco", 100, 9, np.random.default_rng(SEED), lost=100))
    first = write_outputs(results, tmp_path / "run", draws=DRAWS)
    assert {"results_json", "results_csv", "report", "rtf_vs_balls"} <= set(first)
    assert all(p.stat().st_size > 0 for p in first.values())
    again = write_outputs(ExperimentResults.from_json(first["results_json"]),
                          tmp_path / "again", draws=DRAWS)
    for key in ("report", "results_json", "results_csv"):
        assert again[key].read_text() == first[key].read_text()
    saved = ExperimentResults.from_json(first["results_json"])
    assert all(t.chi2 is not None for t in saved.trials if t.settled)


def test_empty_results_still_render(tmp_path: Path) -> None:
    written = write_outputs(ExperimentResults(), tmp_path)
    assert "No trials" in written["report"].read_text()


def test_configurations_of_one_engine_get_qualified_labels() -> None:
    rng = np.random.default_rng(SEED)
    trials = [make_trial("mujoco", 50, 0, rng), make_trial("pybullet", 50, 0, rng)]
    trials.append(TrialRecord.from_dict({**trials[0].to_dict(), "release": "stream"}))
    labels = [s.label for s in summarise(trials, draws=DRAWS)]
    assert labels == ["mujoco [paper, all-at-once]", "mujoco [paper, stream]", "pybullet"]


def test_a_ball_count_where_every_ball_was_lost_fails_fidelity() -> None:
    rng = np.random.default_rng(SEED)
    trials = [make_trial("mujoco", 100, 0, rng), make_trial("mujoco", 20, 0, rng, lost=20)]
    (summary,) = summarise(trials, draws=DRAWS)
    assert summary.groups[0].pooled is None and summary.groups[0].chi2_median is None
    fidelity = judge(summary).checks[0]
    assert not fidelity.passed and "20 balls: no ball settled" in fidelity.detail


def test_lost_by_reason_must_add_up() -> None:
    data = make_trial("mujoco", 30, 0, np.random.default_rng(SEED), lost=2).to_dict()
    with pytest.raises(RecordError, match="lost_by_reason"):
        TrialRecord.from_dict({**data, "lost_by_reason": {"nan": 1}})


def test_the_package_imports_no_simulator_network_or_pyplot() -> None:
    forbidden = ("zenoh", "mujoco", "pybullet", "galton.protocol", "galton.client",
                 "galton.daemon", "matplotlib.pyplot")
    code = ("import sys, galton.analysis; "
            f"print([m for m in sys.modules if m.startswith({forbidden!r})])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
