"""Everything a benchmark run leaves behind, from one ExperimentResults.

``write_outputs`` is what ``galton-client bench`` calls after a run and ``galton-client report
RESULTS_JSON`` calls on a saved run; both give the same files for the same results.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from galton.analysis import stats
from galton.analysis.plots import plot_all
from galton.analysis.records import ExperimentResults
from galton.analysis.report import render_report, write_csv
from galton.analysis.summary import score_trials, summarise
from galton.analysis.verdict import judge_all

RESULTS_JSON = "results.json"
RESULTS_CSV = "results.csv"
REPORT_MD = "report.md"


def score_results(results: ExperimentResults, draws: int = stats.DEFAULT_DRAWS,
                  seed: int = stats.DEFAULT_SEED) -> ExperimentResults:
    """A copy whose trials carry chi2 and p-values (trials already scored are kept)."""
    return replace(results, trials=score_trials(results.trials, draws, seed))


def write_outputs(results: ExperimentResults, out_dir: str | Path,
                  draws: int = stats.DEFAULT_DRAWS,
                  seed: int = stats.DEFAULT_SEED) -> dict[str, Path]:
    """Write results.json (scored), results.csv, report.md and the PNGs; return their paths.
    The report shows the board pictures the results name (galton-client bench renders them
    beside the report).

    Keys: "results_json", "results_csv", "report", and each plot's file stem.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    scored = score_results(results, draws, seed)
    summaries = summarise(scored.trials, draws, seed)
    plots = plot_all(scored.trials, out, draws, seed)
    text = render_report(scored, summaries, judge_all(summaries), [p.name for p in plots],
                         draws, seed)
    report = out / REPORT_MD
    report.write_text(text, encoding="utf-8")
    written = {"results_json": scored.to_json(out / RESULTS_JSON),
               "results_csv": write_csv(scored.trials, out / RESULTS_CSV), "report": report}
    return written | {p.stem: p for p in plots}
