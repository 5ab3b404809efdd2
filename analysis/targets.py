"""The fidelity targets: the one definition of a pass, per engine configuration and ball count.

A cell (engine, board, release mode, ball count) passes when it meets every target the
project set itself against the paper's best simulator (issue 5):

* the Monte Carlo p of the counts pooled over its repetitions above ``MIN_POOLED_P``;
* the median per-trial chi-squared below Webots' published score, ``MAX_CHI2_MEDIAN``;
* no ball lost, and none still moving or resting on a pin at the sim-time cap.

Each cell is held to the level on its own, not Bonferroni-corrected over the ball counts of
a run: at the paper's scale (100 balls x 10) a perfect binomial sampler then passes 95 % of
runs, whatever else the results hold. At 500 balls and more the reference is the board's
own physical law, which is not the binomial (an exact lone-ball model passes about one
500 x 10 run in five), so a family-wise guarantee against the binomial would promise
nothing there; a pass is one run's verdict. ``galton-client check`` prints these verdicts
and the report's fidelity check is built from them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from galton.analysis import stats
from galton.analysis.errors import RecordError
from galton.analysis.formatting import balls_text
from galton.analysis.published import PUBLISHED_TABLE2
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.summary import EngineSummary, GroupSummary, summarise

MIN_POOLED_P = stats.ALPHA
MAX_CHI2_MEDIAN = next(row.chi2 for row in PUBLISHED_TABLE2 if row.simulator == "Webots")
TARGETS_TEXT = (f"pooled p > {MIN_POOLED_P}, median chi2 < {MAX_CHI2_MEDIAN}, "
                "0 lost, 0 unsettled")
NO_BALL_SETTLED = "no ball settled"


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
        if self.pooled_p is None or self.chi2_median is None:
            out.append(NO_BALL_SETTLED)
        else:
            if self.pooled_p <= MIN_POOLED_P:
                out.append(f"pooled p {self.pooled_p:.3g} <= {MIN_POOLED_P}")
            if self.chi2_median >= MAX_CHI2_MEDIAN:
                out.append(f"median chi2 {self.chi2_median:.2f} >= {MAX_CHI2_MEDIAN}")
        if self.lost:
            out.append(f"{self.lost} lost")
        if self.unsettled:
            out.append(f"{self.unsettled} unsettled")
        return out

    @property
    def passed(self) -> bool:
        """True when the cell meets every target."""
        return not self.misses

    def line(self) -> str:
        """The cell's figures and whether it meets every target, on one line."""
        p, chi2 = _figure(self.pooled_p, ".3f"), _figure(self.chi2_median, ".2f")
        verdict = "met" if self.passed else "NOT met: " + "; ".join(self.misses)
        return (f"{self.engine:9} {self.board:6} {self.release:12} {self.balls:5} x "
                f"{self.trials:<3} "
                f"pooled p {p:>6}  median chi2 {chi2:>6}  lost {self.lost}  "
                f"unsettled {self.unsettled}  {verdict}")

    def miss_text(self) -> str:
        """'100 balls: 2 lost; 1 unsettled': the cell's misses in a sentence."""
        return f"{balls_text(self.balls)}: " + "; ".join(self.misses)

    def to_dict(self) -> dict[str, Any]:
        """The cell's figures, its misses and whether it passed, JSON-ready."""
        return {**asdict(self), "passed": self.passed, "misses": self.misses}


def cell_verdict(summary: EngineSummary, group: GroupSummary) -> CellVerdict:
    """The targets read off one ball count's summary."""
    if group.balls is None:
        raise RecordError("a cell is one ball count: the pool over all counts has no verdict")
    return CellVerdict(
        engine=summary.engine, board=summary.board, release=summary.release, balls=group.balls,
        trials=group.trials, pooled_p=group.pooled.p_monte_carlo if group.pooled else None,
        chi2_median=group.chi2_median, lost=group.lost, unsettled=group.unsettled)


def summary_cells(summary: EngineSummary) -> list[CellVerdict]:
    """One verdict per ball count of one engine configuration."""
    return [cell_verdict(summary, group) for group in summary.groups]


def verdicts(trials: Sequence[TrialRecord]) -> list[CellVerdict]:
    """One verdict per engine configuration and ball count, in the report's order."""
    return [cell for summary in summarise(trials) for cell in summary_cells(summary)]


def load_trials(paths: Sequence[str | Path]) -> list[TrialRecord]:
    """The trials of every results file (a folder stands for its results.json).

    Raises RecordError when a file cannot be read or the files hold no trial at all.
    """
    trials: list[TrialRecord] = []
    for name in paths:
        path = Path(name)
        trials += ExperimentResults.from_json(path / "results.json" if path.is_dir()
                                              else path).trials
    if not trials:
        raise RecordError(f"the results hold no trial: {', '.join(map(str, paths))}; "
                          "give a results.json written by galton-client bench")
    return trials
