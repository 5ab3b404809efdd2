"""The shape of a bin distribution beyond its width: how flat it is, and what that says.

A ball that makes ``rows`` independent fair left/right choices lands with the binomial law,
whose excess kurtosis is exactly -2 / rows. A walk whose choices are correlated (a lively
ball that keeps its sideways motion from pin to pin, or skips one) behaves like fewer,
larger independent choices: its law is flatter, with excess kurtosis -2 / n for some
n < rows, even when its width is right. ``effective_rows`` reads that n back, so a flat
shape gets a physical reading ("like 6 independent rows, not 11") rather than only a p.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from galton.analysis.errors import NoSettledBallsError
from galton.analysis.stats import DEFAULT_SEED, ROWS, SeedLike, bin_probabilities, check_counts

NULL_DRAWS = 2_000


@dataclass(frozen=True)
class Flatness:
    """A table's excess kurtosis, beside what the binomial gives at the same number of balls."""

    excess_kurtosis: float
    effective_rows: float  # inf when the table is not flatter than a normal law
    binomial_excess_kurtosis: float  # -2 / rows
    null_low: float  # 2.5 % and 97.5 % quantiles of a binomial board's tables of this size
    null_high: float

    @property
    def outside_null(self) -> bool:
        return not self.null_low <= self.excess_kurtosis <= self.null_high


def width(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> float:
    """Standard deviation of the bin index over the settled balls; the binomial's is
    sqrt(rows) / 2, so a width says at once whether a law is too narrow or too wide."""
    table = check_counts(counts, rows).astype(float)
    settled = table.sum()
    if settled < 1:
        raise NoSettledBallsError("a width needs settled balls")
    bins = np.arange(len(table))
    mean = table @ bins / settled
    return float(np.sqrt(table @ (bins - mean) ** 2 / settled))


def excess_kurtosis(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> float:
    """Fourth standardised moment of the bin index, minus 3 (a normal law gives 0)."""
    table = check_counts(counts, rows).astype(float)
    settled = table.sum()
    if settled < 2:
        raise NoSettledBallsError("a kurtosis needs >= 2 settled balls")
    return float(_excess_kurtosis_rows(table[None, :])[0])


def effective_rows(kurtosis: float) -> float:
    """How many independent fair left/right choices give this flatness (-2 / kurtosis)."""
    return -2.0 / kurtosis if kurtosis < 0 else float("inf")


def flatness(counts: Sequence[int] | np.ndarray, rows: int = ROWS, draws: int = NULL_DRAWS,
             seed: SeedLike = DEFAULT_SEED) -> Flatness:
    """The table's flatness and the 95 % range a binomial board gives with as many balls
    (seeded multinomial draws), so that a departure is read against sampling noise."""
    table = check_counts(counts, rows)
    kurtosis = excess_kurtosis(table, rows)
    rng = np.random.default_rng(seed)
    null_tables = rng.multinomial(int(table.sum()), bin_probabilities(rows), size=draws)
    low, high = np.quantile(_excess_kurtosis_rows(null_tables.astype(float)), [0.025, 0.975])
    return Flatness(kurtosis, effective_rows(kurtosis), -2.0 / rows, float(low), float(high))


def _excess_kurtosis_rows(tables: np.ndarray) -> np.ndarray:
    bins = np.arange(tables.shape[1], dtype=float)
    settled = tables.sum(axis=1, keepdims=True)
    weights = tables / settled
    mean = (weights * bins).sum(axis=1, keepdims=True)
    deviations = bins - mean
    variance = (weights * deviations**2).sum(axis=1)
    fourth = (weights * deviations**4).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(variance > 0, fourth / variance**2 - 3.0, np.nan)
