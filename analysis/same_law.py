"""Do two sets of bin counts come from the same law?

The binomial is not the only reference worth testing against: on the ``paper`` board an
exact, engine-free model of a lone ball gives a flat law at the binomial's width, and an
engine that agrees with it is as faithful as mechanics allows. This is Pearson's test of
homogeneity on the 2 x bins table (``scipy.stats.chi2_contingency``), with each side's
outer bins merged, because the binomial's outermost bins hold a ball in 2,048 and a
sparse cell would make the asymptotic p meaningless.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats as sps

from galton.analysis.errors import CountsError, TooFewBallsError
from galton.analysis.stats import ROWS, check_counts

DEFAULT_TAIL_BINS = 2


@dataclass(frozen=True)
class Homogeneity:
    """Pearson's chi-squared of two tables against their common law, its freedom and p."""

    chi2: float
    dof: int
    p_value: float


def merge_tails(table: np.ndarray, tail_bins: int) -> np.ndarray:
    """The table with its ``tail_bins`` outermost bins on each side summed into one."""
    if tail_bins < 1 or 2 * tail_bins >= table.size:
        raise CountsError(f"tail_bins must be 1..{(table.size - 1) // 2} for {table.size} "
                          f"bins, got {tail_bins}")
    inner = table[tail_bins:table.size - tail_bins]
    return np.concatenate(([table[:tail_bins].sum()], inner, [table[-tail_bins:].sum()]))


def homogeneity(counts_a: Sequence[int] | np.ndarray, counts_b: Sequence[int] | np.ndarray,
                rows: int = ROWS, tail_bins: int = DEFAULT_TAIL_BINS) -> Homogeneity:
    """Whether ``counts_a`` and ``counts_b`` are samples of one law (a small p says not).

    Both tables need balls, and every merged bin needs a ball in one of them: an empty
    column has no expected count to test against.
    """
    tables = [merge_tails(check_counts(c, rows), tail_bins) for c in (counts_a, counts_b)]
    for name, table in zip(("counts_a", "counts_b"), tables, strict=True):
        if table.sum() == 0:
            raise TooFewBallsError(f"{name} holds no ball: there is no law to compare")
    pair = np.vstack(tables)
    if np.any(pair.sum(axis=0) == 0):
        raise TooFewBallsError(f"a merged bin is empty in both tables: {pair.tolist()}; "
                               f"merge more tail bins")
    chi2, p_value, dof, _ = sps.chi2_contingency(pair, correction=False)
    return Homogeneity(chi2=float(chi2), dof=int(dof), p_value=float(p_value))
