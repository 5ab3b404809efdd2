"""Fidelity maps: the benchmark over a grid of one or two engine parameters.

Trials carry the engine parameters they ran with (``TrialRecord.settings``); a sweep
groups them into cells by the swept parameters' values and scores each cell over its
repetitions: pooled chi-squared, Monte Carlo p, median per-trial chi-squared, lost and
unsettled balls.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from galton.analysis import stats
from galton.analysis.errors import AnalysisError
from galton.analysis.formatting import fmt
from galton.analysis.records import TrialRecord
from galton.analysis.summary import trial_seed


@dataclass(frozen=True)
class SweepAxis:
    """One swept engine parameter and its values, in order."""

    name: str
    values: tuple[Any, ...]


@dataclass(frozen=True)
class SweepCell:
    """The trials of one engine at one point of the grid, scored over repetitions."""

    engine: str
    point: tuple[Any, ...]
    trials: int
    released: int
    lost: int
    unsettled: int
    chi2_pooled: float | None
    p_monte_carlo: float | None
    chi2_median: float | None
    rtf_mean: float | None

    @property
    def lost_percent(self) -> float:
        return 100.0 * self.lost / self.released if self.released else 0.0

    def to_dict(self) -> dict[str, Any]:
        return {"engine": self.engine, "point": list(self.point), "trials": self.trials,
                "released": self.released, "lost": self.lost, "lost_percent": self.lost_percent,
                "unsettled": self.unsettled, "chi2_pooled": self.chi2_pooled,
                "p_monte_carlo": self.p_monte_carlo, "chi2_median": self.chi2_median,
                "rtf_mean": self.rtf_mean}


def _value_key(value: Any) -> Any:
    return tuple(value) if isinstance(value, list) else value


def sweep_cells(trials: Sequence[TrialRecord], axes: Sequence[SweepAxis],
                draws: int = stats.DEFAULT_DRAWS,
                seed: int = stats.DEFAULT_SEED) -> list[SweepCell]:
    """One cell per engine and grid point, in engine then grid order."""
    if not 1 <= len(axes) <= 2:
        raise AnalysisError(f"a sweep has one or two axes, got {len(axes)}")
    groups: dict[tuple[str, tuple[Any, ...]], list[TrialRecord]] = {}
    for trial in trials:
        missing = [a.name for a in axes if a.name not in trial.settings]
        if missing:
            raise AnalysisError(f"trial {trial.engine} rep {trial.repetition} has no setting "
                                f"{missing[0]!r}: was it run by a sweep over it?")
        point = tuple(_value_key(trial.settings[a.name]) for a in axes)
        groups.setdefault((trial.engine, point), []).append(trial)
    return [_cell(engine, point, group, draws, seed)
            for (engine, point), group in groups.items()]


def _cell(engine: str, point: tuple[Any, ...], trials: list[TrialRecord], draws: int,
          seed: int) -> SweepCell:
    rows = trials[0].rows
    tables = [t.counts for t in trials if t.settled > 0]
    fit = None
    if tables and sum(map(sum, tables)) > 0:
        rng = np.random.default_rng(trial_seed(seed, engine, *map(str, point)))
        fit = stats.pooled_over_repetitions(tables, rows, draws, rng)
    chi2s = [stats.chi2_statistic(t.counts, rows) for t in trials if t.settled > 0]
    rtfs = [t.rtf for t in trials if t.rtf is not None]
    return SweepCell(
        engine=engine, point=point, trials=len(trials), released=sum(t.balls for t in trials),
        lost=sum(t.lost for t in trials), unsettled=sum(t.unsettled for t in trials),
        chi2_pooled=fit.chi2 if fit else None, p_monte_carlo=fit.p_monte_carlo if fit else None,
        chi2_median=float(np.median(chi2s)) if chi2s else None,
        rtf_mean=float(np.mean(rtfs)) if rtfs else None)


def sweep_table(cells: Sequence[SweepCell], axes: Sequence[SweepAxis]) -> str:
    """A Markdown table of every cell."""
    head = ["engine", *(a.name for a in axes), "pooled χ²", "Monte Carlo p",
            "median χ² per trial", "lost %", "unsettled", "RTF"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    for c in cells:
        values = [c.engine, *(str(v) for v in c.point), fmt(c.chi2_pooled, 2),
                  fmt(c.p_monte_carlo, 3), fmt(c.chi2_median, 2), f"{c.lost_percent:.1f}",
                  str(c.unsettled), fmt(c.rtf_mean, 2)]
        lines.append("| " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


def plot_sweep(cells: Sequence[SweepCell], axes: Sequence[SweepAxis], engine: str,
               out_dir: str | Path) -> Path:
    """A fidelity map for one engine: Monte Carlo p per cell, χ² and lost % written in."""
    mine = {c.point: c for c in cells if c.engine == engine}
    xs = axes[0].values
    ys = axes[1].values if len(axes) == 2 else ("",)
    grid = np.full((len(ys), len(xs)), np.nan)
    fig = Figure(figsize=(1.6 + 1.3 * len(xs), 1.6 + 0.9 * len(ys)))
    ax = fig.add_subplot()
    for i, y in enumerate(ys):
        for j, x in enumerate(xs):
            point = (_value_key(x),) if len(axes) == 1 else (_value_key(x), _value_key(y))
            cell = mine.get(point)
            if cell is None:
                continue
            grid[i, j] = cell.p_monte_carlo if cell.p_monte_carlo is not None else np.nan
            chi2 = "–" if cell.chi2_pooled is None else f"{cell.chi2_pooled:.1f}"
            ax.text(j, i, f"χ²={chi2}\np={fmt(cell.p_monte_carlo, 3)}\n"
                    f"lost {cell.lost_percent:.1f}%", ha="center", va="center", fontsize=7)
    image = ax.imshow(grid, cmap="RdYlGn", vmin=0.0, vmax=0.2, origin="lower", aspect="auto")
    fig.colorbar(image, ax=ax, label="pooled Monte Carlo p (green: faithful, > 0.05)")
    ax.set_xticks(range(len(xs)), [str(x) for x in xs])
    ax.set_xlabel(axes[0].name)
    ax.set_yticks(range(len(ys)), [str(y) for y in ys])
    ax.set_ylabel(axes[1].name if len(axes) == 2 else "")
    ax.set_title(f"{engine}: fidelity map", fontsize=10)
    fig.tight_layout()
    path = Path(out_dir) / f"sweep_{engine}.png"
    fig.savefig(path, dpi=110)
    return path
