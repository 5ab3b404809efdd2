"""PNG figures like the paper's Fig. 3 (histograms) and Fig. 4 (RTF), plus CPU and memory.

Figures are built on ``matplotlib.figure.Figure`` directly, never through pyplot, so no global
backend is chosen and no figure outlives its function.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from galton.analysis import stats
from galton.analysis.formatting import balls_text, p_equals
from galton.analysis.records import TrialRecord, has_curve
from galton.analysis.summary import config_key, config_labels, trial_seed

DPI = 110
LOG_SPAN = 10.0
HISTOGRAM_PREFIX = "histogram_"
RTF_FILE = "rtf_vs_balls.png"
RESOURCES_FILE = "resources_vs_balls.png"


def file_stem(label: str) -> str:
    """A file-name-safe version of an engine label."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", label).strip("_") or "engine"


def _by_config(trials: Sequence[TrialRecord]) -> dict[str, list[TrialRecord]]:
    labels = config_labels(config_key(t) for t in trials)
    return {label: [t for t in trials if config_key(t) == key]
            for key, label in sorted(labels.items(), key=lambda item: item[1])}


def _save(fig: Figure, path: Path) -> Path:
    fig.savefig(path, dpi=DPI)
    fig.clear()
    return path


def _histogram_axes(ax: Axes, trials: Sequence[TrialRecord], draws: int, seed: int) -> None:
    """Pooled observed counts as bars, binomial expectation as a line, the test in the title."""
    first = trials[0]
    pooled = stats.sum_over_repetitions([t.counts for t in trials], first.rows)
    bins = np.arange(first.rows + 1)
    ax.bar(bins, pooled, color="tab:blue", alpha=0.7, label="observed (pooled)")
    ax.plot(bins, stats.expected_counts(int(pooled.sum()), first.rows), "k.-",
            label=f"expected Binomial({first.rows}, ½)")
    title = f"{balls_text(first.balls)} × {len(trials)} trials"
    if pooled.sum() > 0:
        rng = np.random.default_rng(trial_seed(seed, *config_key(first), first.balls))
        fit = stats.goodness_of_fit(pooled, first.rows, draws * stats.POOLED_DRAWS_FACTOR,
                                    rng)
        title += f"\npooled χ² = {fit.chi2:.1f}, Monte Carlo {p_equals(fit.p_monte_carlo)}"
    ax.set_title(title, fontsize=9)
    ax.set_xticks(bins)
    ax.set_xlabel("bin")
    ax.set_ylabel("balls")


def plot_histograms(trials: Sequence[TrialRecord], out_dir: str | Path,
                    draws: int = stats.DEFAULT_DRAWS,
                    seed: int = stats.DEFAULT_SEED) -> list[Path]:
    """One PNG per engine: a panel per ball count of pooled observed vs expected counts."""
    paths = []
    for label, group in _by_config(trials).items():
        counts = sorted({t.balls for t in group})
        columns = min(3, len(counts))
        rows = math.ceil(len(counts) / columns)
        fig = Figure(figsize=(4.2 * columns, 3.4 * rows), layout="constrained")
        axes = fig.subplots(rows, columns, squeeze=False).ravel()
        for ax, n in zip(axes, counts, strict=False):
            _histogram_axes(ax, [t for t in group if t.balls == n], draws, seed)
        for ax in axes[len(counts):]:
            ax.set_visible(False)
        axes[0].legend(fontsize=7)
        fig.suptitle(f"{label}: observed vs expected (Fig. 3)")
        paths.append(_save(fig, Path(out_dir) / f"{HISTOGRAM_PREFIX}{file_stem(label)}.png"))
    return paths


def _series(trials: Sequence[TrialRecord], attr: str,
            scale: float = 1.0) -> tuple[list[int], list[float], list[float], list[float]]:
    """Ball counts and the mean, min and max of ``attr`` at each, skipping missing values."""
    xs, means, lows, highs = [], [], [], []
    for n in sorted({t.balls for t in trials}):
        values = [getattr(t, attr) * scale for t in trials
                  if t.balls == n and getattr(t, attr) is not None]
        if values:
            xs.append(n)
            means.append(float(np.mean(values)))
            lows.append(min(values))
            highs.append(max(values))
    return xs, means, lows, highs


def _plot_series(ax: Axes, label: str, trials: Sequence[TrialRecord], attr: str,
                 scale: float = 1.0) -> list[float]:
    """Mean with min–max error bars; returns the values drawn, to choose the scales."""
    xs, means, lows, highs = _series(trials, attr, scale)
    if xs:
        # Clipped: the mean of equal values can round just outside their min or max.
        errors = np.clip([np.subtract(means, lows), np.subtract(highs, means)], 0.0, None)
        ax.errorbar(xs, means, yerr=errors, marker="o", capsize=3, label=label)
    return [*lows, *highs]


def _legend(ax: Axes) -> None:
    """A legend only where something is labelled (an empty one warns)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)


def _log_if_wide(ax: Axes, xs: Sequence[float], ys: Sequence[float]) -> None:
    """Log axes where values span more than LOG_SPAN times."""
    for values, set_scale in ((xs, ax.set_xscale), (ys, ax.set_yscale)):
        positive = [v for v in values if v > 0]
        if positive and max(positive) / min(positive) > LOG_SPAN:
            set_scale("log")


def plot_rtf(trials: Sequence[TrialRecord], out_dir: str | Path) -> Path:
    """RTF vs balls per engine (Fig. 4): mean, min–max bars, dashed line at real time."""
    fig = Figure(figsize=(6.4, 4.2), layout="constrained")
    ax = fig.subplots()
    ys: list[float] = []
    for label, group in _by_config(trials).items():
        ys += _plot_series(ax, label, group, "rtf")
    ax.axhline(1.0, color="grey", linestyle="--", label="real time (RTF 1)")
    _log_if_wide(ax, [t.balls for t in trials], [*ys, 1.0])
    ax.set_xlabel("balls released")
    ax.set_ylabel("real-time factor (sim time / wall time)")
    ax.set_title("Real-time factor vs number of balls (Fig. 4)")
    _legend(ax)
    return _save(fig, Path(out_dir) / RTF_FILE)


def plot_resources(trials: Sequence[TrialRecord], out_dir: str | Path) -> Path:
    """Mean CPU % and peak RSS (MB) vs balls per engine, with min–max bars."""
    fig = Figure(figsize=(10, 4), layout="constrained")
    cpu_ax, rss_ax = fig.subplots(1, 2)
    for label, group in _by_config(trials).items():
        _plot_series(cpu_ax, label, group, "cpu_percent_mean")
        _plot_series(rss_ax, label, group, "peak_rss_bytes", scale=1e-6)
    cpu_ax.axhline(100.0, color="grey", linestyle="--", label="one core")
    for ax, name in ((cpu_ax, "mean CPU (% of one core)"), (rss_ax, "peak RSS (MB)")):
        _log_if_wide(ax, [t.balls for t in trials], [])
        ax.set_ylim(bottom=0)
        ax.set_xlabel("balls released")
        ax.set_ylabel(name)
        _legend(ax)
    fig.suptitle("Footprint vs number of balls")
    return _save(fig, Path(out_dir) / RESOURCES_FILE)


def plot_all(trials: Sequence[TrialRecord], out_dir: str | Path,
             draws: int = stats.DEFAULT_DRAWS, seed: int = stats.DEFAULT_SEED) -> list[Path]:
    """Every figure; returns the paths written (none when there are no trials). The RTF
    and footprint curves need two ball counts at least: one count would draw one point."""
    if not trials:
        return []
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    histograms = plot_histograms(trials, out_dir, draws, seed)
    if not has_curve(trials):
        return histograms
    return [*histograms, plot_rtf(trials, out_dir), plot_resources(trials, out_dir)]

