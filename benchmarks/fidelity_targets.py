"""Does a bench run meet the fidelity targets? Recomputed from its results.json alone.

Usage: python benchmarks/fidelity_targets.py RESULTS [RESULTS ...]

Each RESULTS is a results.json written by ``galton-client bench`` (or the folder holding
one). Their trials are pooled and summarised as the bench's report does (same Monte Carlo
draws and seeds, so the same p), and each engine, release mode and ball count is held to
the targets the project set itself against the paper's best simulator:

* the Monte Carlo p of the counts pooled over the repetitions above 0.05;
* the median per-trial chi-squared below Webots' published 16.64;
* no ball lost, and no ball still moving or resting on a pin at the sim-time cap.

It prints one line per cell and exits 1 when any cell misses a target, so a script can
gate on it. A pass is one run's verdict: docs/PHYSICS.md ("How robust a pass is") says how
often a run of 500 balls x 10 passes with other seeds.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

from galton.analysis import stats
from galton.analysis.errors import RecordError
from galton.analysis.published import PUBLISHED_TABLE2
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.summary import EngineSummary, GroupSummary, summarise

MIN_POOLED_P = stats.ALPHA
WEBOTS_CHI2 = next(row.chi2 for row in PUBLISHED_TABLE2 if row.simulator == "Webots")


def _figure(value: float | None, spec: str) -> str:
    """A figure, or '-' where none could be computed (no ball settled)."""
    return "-" if value is None else format(value, spec)


@dataclass(frozen=True)
class CellVerdict:
    """One engine, release mode and ball count against the targets."""

    engine: str
    board: str
    release: str
    balls: int
    trials: int
    pooled_p: float | None
    chi2_median: float | None
    lost: int
    unsettled: int

    @property
    def misses(self) -> list[str]:
        """The targets this cell misses, each saying by how much."""
        out = []
        if self.pooled_p is None or self.pooled_p <= MIN_POOLED_P:
            out.append(f"pooled p {_figure(self.pooled_p, '.3g')} <= {MIN_POOLED_P}")
        if self.chi2_median is None or self.chi2_median >= WEBOTS_CHI2:
            out.append(f"median chi2 {_figure(self.chi2_median, '.2f')} >= {WEBOTS_CHI2}")
        if self.lost:
            out.append(f"{self.lost} lost")
        if self.unsettled:
            out.append(f"{self.unsettled} unsettled")
        return out

    def line(self) -> str:
        """The cell's figures and whether it meets every target."""
        p, chi2 = _figure(self.pooled_p, ".3f"), _figure(self.chi2_median, ".2f")
        verdict = "met" if not self.misses else "NOT met: " + "; ".join(self.misses)
        return (f"{self.engine:9} {self.board:6} {self.release:12} {self.balls:5} x "
                f"{self.trials:<3} "
                f"pooled p {p:>6}  median chi2 {chi2:>6}  lost {self.lost}  "
                f"unsettled {self.unsettled}  {verdict}")


def cell_verdict(summary: EngineSummary, group: GroupSummary) -> CellVerdict:
    """The targets read off one ball count's summary."""
    assert group.balls is not None
    return CellVerdict(
        engine=summary.engine, board=summary.board, release=summary.release, balls=group.balls,
        trials=group.trials, pooled_p=group.pooled.p_monte_carlo if group.pooled else None,
        chi2_median=group.chi2_median, lost=group.lost, unsettled=group.unsettled)


def load_trials(paths: list[str]) -> list[TrialRecord]:
    """The trials of every results file (a folder stands for its results.json)."""
    trials = []
    for name in paths:
        path = Path(name)
        trials += ExperimentResults.from_json(path / "results.json" if path.is_dir()
                                              else path).trials
    return trials


def verdicts(trials: list[TrialRecord]) -> list[CellVerdict]:
    """One verdict per engine configuration and ball count, in the report's order."""
    return [cell_verdict(summary, group) for summary in summarise(trials)
            for group in summary.groups]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results", nargs="+", help="results.json files or their folders")
    args = parser.parse_args(argv)
    try:
        trials = load_trials(args.results)
    except RecordError as exc:
        parser.error(str(exc))
    if not trials:
        parser.error("the results hold no trial")
    cells = verdicts(trials)
    for cell in cells:
        print(cell.line())
    missed = [c for c in cells if c.misses]
    print(f"{len(cells) - len(missed)} of {len(cells)} cells meet every target "
          f"(pooled p > {MIN_POOLED_P}, median chi2 < {WEBOTS_CHI2}, 0 lost, 0 unsettled)")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
