"""Every figure of the report card with its 95 % interval, from its repetitions.

* medians of repeated timings: the distribution-free interval of order statistics (with
  fewer than 6 samples no pair of them reaches 95 %, so the interval is their range);
* means of telemetry samples (CPU, memory) and of trials' RTF: Student's t;
* counts of events among opportunities (physics errors): Clopper–Pearson;
* the Galton board's figures: a seeded bootstrap over trials (the χ² median: order
  statistics over trials, as for timings);
* the laws' checks: each check's own tolerance. A check whose error lies within a factor
  ``NEAR_LINE`` of its tolerance, either side, could go either way with another step, seed
  or judgement of the tolerance, so the count of checks passed spans them.

Nothing here is a verdict; ``card_rules`` compares the intervals.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy import stats as sps

from galton.analysis import stats
from galton.analysis.errors import RecordError
from galton.analysis.laws import Check

LEVEL = 0.95
RESAMPLES = 2000  # bootstrap resamples of a trial statistic
P_DRAWS = stats.DEFAULT_DRAWS  # null tables of the pooled p, one null per number of balls
NEAR_LINE = 1.5  # a check within this factor of its tolerance, either side, is at the line
BOOTSTRAP_SEED = 20_261_129


@dataclass(frozen=True)
class Measure:
    """A figure, its 95 % interval and how many repetitions made it."""

    value: float
    low: float
    high: float
    n: int

    def to_dict(self) -> dict[str, float | int]:
        return {"value": self.value, "low": self.low, "high": self.high, "n": self.n}

    @classmethod
    def from_dict(cls, body: Any) -> Measure:
        try:
            return cls(float(body["value"]), float(body["low"]), float(body["high"]),
                       int(body["n"]))
        except (KeyError, TypeError, ValueError) as error:
            raise RecordError(f"a card measure needs value, low, high and n ({error!r}): "
                              f"{body!r}") from error

    @classmethod
    def exact(cls, value: float, n: int = 1) -> Measure:
        return cls(value, value, value, n)

    def overlaps(self, other: Measure) -> bool:
        return self.low <= other.high and other.low <= self.high


def number(value: float) -> str:
    """Three significant digits, whole numbers from 100 up (1385, not 1.38e+03)."""
    if not math.isfinite(value):
        return str(value)
    if abs(value) >= 100:
        return f"{value:.0f}"
    return f"{value:.3g}"


def measure_text(measure: Measure | None, unit: str = "") -> str:
    """``7.89 [6.8–9.12] ms``; ``0 %`` where the interval is the value itself."""
    if measure is None:
        return "not measured"
    shown = number(measure.value)
    if (measure.low, measure.high) != (measure.value, measure.value):
        shown += f" [{number(measure.low)}–{number(measure.high)}]"
    return f"{shown} {unit}".strip() if unit and unit != "checks" else shown


def median_measure(samples: Sequence[float]) -> Measure:
    """The median and its distribution-free interval x(k) .. x(n+1-k)."""
    ordered = sorted(float(s) for s in samples)
    n = len(ordered)
    if n == 0:
        raise RecordError("a median needs at least one sample")
    k = int(sps.binom.ppf((1 - LEVEL) / 2, n, 0.5))  # P(B <= k-1) <= 2.5 %
    low, high = (ordered[0], ordered[-1]) if k < 1 else (ordered[k - 1], ordered[n - k])
    return Measure(statistics.median(ordered), low, high, n)


def mean_measure(samples: Sequence[float]) -> Measure:
    """The mean and its t interval (one sample: no spread known, the interval is it)."""
    values = [float(s) for s in samples]
    n = len(values)
    if n == 0:
        raise RecordError("a mean needs at least one sample")
    mean = statistics.fmean(values)
    if n == 1:
        return Measure.exact(mean)
    half = float(sps.t.ppf((1 + LEVEL) / 2, n - 1)) * statistics.stdev(values) / math.sqrt(n)
    return Measure(mean, mean - half, mean + half, n)


def count_measure(events: int, opportunities: int) -> Measure:
    """``events`` among ``opportunities``, with the Clopper–Pearson interval in events."""
    if opportunities < 1:
        return Measure.exact(float(events), 0)
    tail = (1 - LEVEL) / 2
    low = 0.0 if events == 0 else float(sps.beta.ppf(tail, events,
                                                     opportunities - events + 1))
    high = 1.0 if events >= opportunities else float(sps.beta.ppf(1 - tail, events + 1,
                                                                  opportunities - events))
    return Measure(float(events), low * opportunities, high * opportunities, opportunities)


def laws_measure(checks: Sequence[Check]) -> Measure:
    """Checks passed, spanning those within ``NEAR_LINE`` of their tolerance."""
    passed = sum(c.passed for c in checks)
    near_pass = sum(c.passed and abs(c.error or 0.0) > c.tolerance / NEAR_LINE
                    for c in checks)
    near_fail = sum(not c.passed and c.error is not None and math.isfinite(c.error)
                    and abs(c.error) <= c.tolerance * NEAR_LINE for c in checks)
    return Measure(float(passed), float(passed - near_pass), float(passed + near_fail),
                   len(checks))


@dataclass(frozen=True)
class BoardTrial:
    """What the card keeps of one Galton trial: its bin counts, the balls lost and
    released (enough to recompute every board figure and its bootstrap)."""

    counts: tuple[int, ...]
    lost: int
    balls: int

    def to_dict(self) -> dict[str, Any]:
        return {"counts": list(self.counts), "lost": self.lost, "balls": self.balls}

    @classmethod
    def from_dict(cls, body: Any) -> BoardTrial:
        try:
            return cls(tuple(int(c) for c in body["counts"]), int(body["lost"]),
                       int(body["balls"]))
        except (KeyError, TypeError, ValueError) as error:
            raise RecordError(f"a card's board trial is malformed ({error!r})") from error

    @property
    def settled(self) -> int:
        return sum(self.counts)


@dataclass(frozen=True, eq=False)
class TrialArrays:
    """Trials as arrays, so a statistic runs over thousands of resamples at once."""

    counts: np.ndarray  # trials × bins
    lost: np.ndarray
    balls: np.ndarray

    @classmethod
    def of(cls, trials: Sequence[BoardTrial]) -> TrialArrays:
        return cls(np.array([t.counts for t in trials], dtype=float),
                   np.array([t.lost for t in trials], dtype=float),
                   np.array([t.balls for t in trials], dtype=float))

    def tables(self, picks: np.ndarray) -> np.ndarray:
        """Each resample's summed counts: resamples × bins (``picks``: resamples × trials)."""
        return np.asarray(self.counts[picks].sum(axis=1))


# A statistic of every resample at once: (trials, picks: resamples × trials) -> resamples.
Statistic = Callable[[TrialArrays, np.ndarray], np.ndarray]


def _chi2(tables: np.ndarray) -> np.ndarray:
    totals = tables.sum(axis=-1, keepdims=True)
    expected = stats.bin_probabilities(tables.shape[-1] - 1) * totals
    return np.asarray((((tables - expected) ** 2) / expected).sum(axis=-1))


def chi2_median(trials: TrialArrays, picks: np.ndarray) -> np.ndarray:
    """The median of the picked trials' χ² (the paper's statistic, per trial)."""
    return np.asarray(np.median(_chi2(trials.counts)[picks], axis=1))


def _w(tables: np.ndarray, noise: float) -> np.ndarray:
    excess = _chi2(tables) - noise * (tables.shape[-1] - 1)
    return np.asarray(np.sqrt(np.maximum(0.0, excess) / tables.sum(axis=-1)))


def pooled_w(trials: TrialArrays, picks: np.ndarray) -> np.ndarray:
    """Cohen's w (bias-corrected) of the summed counts: 0 for the binomial, whatever the
    number of balls, so fewer trials widen its interval without moving it."""
    return _w(trials.tables(picks), 1.0)


def resampled_w(trials: TrialArrays, picks: np.ndarray) -> np.ndarray:
    """w of a bootstrap resample: resampling trials adds a second multinomial's worth of
    noise to the summed counts (χ² grows by about its degrees of freedom again), so the
    correction is doubled; otherwise the interval of a perfect board would not hold 0."""
    return _w(trials.tables(picks), 2.0)


def lost_percent(trials: TrialArrays, picks: np.ndarray) -> np.ndarray:
    released = trials.balls[picks].sum(axis=1)
    return np.asarray(100.0 * trials.lost[picks].sum(axis=1) / np.maximum(released, 1.0))


def _pooled_p(seed: int) -> Statistic:
    """The Monte Carlo p of the summed counts, one seeded null per number of balls."""
    nulls: dict[int, np.ndarray] = {}

    def p(trials: TrialArrays, picks: np.ndarray) -> np.ndarray:
        tables = trials.tables(picks)
        out = np.empty(len(tables))
        for i, (table, observed) in enumerate(zip(tables, _chi2(tables), strict=True)):
            settled = int(table.sum())
            if settled not in nulls:
                nulls[settled] = np.sort(stats.null_statistics(
                    settled, len(table) - 1, P_DRAWS, np.random.default_rng([seed, settled])))
            null = nulls[settled]
            beyond = len(null) - np.searchsorted(null, observed - 1e-9 * max(1.0, observed))
            out[i] = (beyond + 1) / (len(null) + 1)
        return out
    return p


def _picks(rng: np.random.Generator, trials: int, resamples: int) -> np.ndarray:
    return rng.integers(0, trials, (resamples, trials))


def bootstrap_measure(trials: Sequence[BoardTrial], statistic: Statistic,
                      rng: np.random.Generator, resamples: int = RESAMPLES,
                      replica: Statistic | None = None) -> Measure:
    """The statistic of all trials, and the percentile interval of its resamples
    (``replica``: the statistic of a resample, where it differs)."""
    arrays = TrialArrays.of(trials)
    value = float(statistic(arrays, np.arange(len(trials))[None, :])[0])
    if len(trials) < 2:
        return Measure.exact(value, len(trials))
    replicas = (replica or statistic)(arrays, _picks(rng, len(trials), resamples))
    tail = 100 * (1 - LEVEL) / 2
    low, high = np.percentile(replicas, [tail, 100 - tail])
    return Measure(value, min(float(low), value), max(float(high), value), len(trials))


def board_measures(trials: Sequence[BoardTrial], prefix: str, seed: int
                   ) -> dict[str, Measure | None]:
    """``<prefix>_chi2_median``, ``_effect_w``, ``_pooled_p`` and ``_lost_percent``, each
    over the trials (None where no ball settled)."""
    rng = np.random.default_rng([BOOTSTRAP_SEED, seed])
    settled = [t for t in trials if t.settled]
    lost = bootstrap_measure(trials, lost_percent, rng) if trials else None
    if not settled:
        return {f"{prefix}_chi2_median": None, f"{prefix}_effect_w": None,
                f"{prefix}_pooled_p": None, f"{prefix}_lost_percent": lost}
    chi2s = _chi2(TrialArrays.of(settled).counts)
    return {f"{prefix}_chi2_median": median_measure([float(c) for c in chi2s]),
            f"{prefix}_effect_w": bootstrap_measure(settled, pooled_w, rng, replica=resampled_w),
            f"{prefix}_pooled_p": bootstrap_measure(settled, _pooled_p(seed), rng),
            f"{prefix}_lost_percent": lost}


def order_probability(ahead: Sequence[BoardTrial], behind: Sequence[BoardTrial],
                      statistic: Statistic, lower_is_better: bool, seed: int = 0,
                      resamples: int = RESAMPLES) -> float:
    """How often, resampling each engine's trials, the engine ``ahead`` stays ahead
    (an exact tie counts half)."""
    rng = np.random.default_rng([BOOTSTRAP_SEED, seed, 1])
    a = statistic(TrialArrays.of(ahead), _picks(rng, len(ahead), resamples))
    b = statistic(TrialArrays.of(behind), _picks(rng, len(behind), resamples))
    kept = (a < b) if lower_is_better else (a > b)
    return float(np.mean(kept + 0.5 * (a == b)))
