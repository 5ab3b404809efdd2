"""Goodness of fit of Galton-board bin counts to Binomial(rows, 1/2).

Two statistics sit side by side, because the paper's test is poorly calibrated:

* the paper's statistic, chi2 = sum (O - E)^2 / E over all rows + 1 bins, compared with the
  chi-squared distribution with bins - 1 degrees of freedom (``p_asymptotic``). With 100
  balls, six of twelve expected counts are below 5 and one ball in an outer bin adds 18.5,
  so a perfect binomial board fails this test about 12 % of the time instead of 5 %;
* honest p-values: Monte Carlo under the exact multinomial (``p_monte_carlo``) and the
  asymptotic test after merging sparse tail bins until every expected count is >= 5
  (``p_pooled_tails``).

"Per trial" functions test one trial's counts; ``pooled_over_repetitions`` sums the counts of
several trials (repetitions) and tests that sum.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats as sps
from scipy.optimize import brentq

from galton.analysis.errors import CountsError, NoSettledBallsError, TooFewBallsError

ROWS = 11
ALPHA = 0.05
MIN_EXPECTED = 5.0
DEFAULT_DRAWS = 20_000
# The pooled test decides the fidelity verdict, so it draws this many times more tables: at
# p near 0.05 the estimate's standard error falls from 0.0015 to 0.0005, and a verdict on
# the threshold no longer turns on the Monte Carlo seed.
POOLED_DRAWS_FACTOR = 10
DEFAULT_SEED = 20_240_511
# Relative slack so that tables equal to the observed one count as "at least as extreme"
# despite floating-point summation order (as R's chisq.test does).
_TIE_TOLERANCE = 1e-9

SeedLike = int | np.random.Generator | None


def bin_probabilities(rows: int = ROWS) -> np.ndarray:
    """Binomial(rows, 1/2) pmf, exact in floating point and exactly symmetric."""
    if rows < 1:
        raise CountsError(f"a board needs at least 1 row of pins, got rows={rows}")
    return np.array([math.comb(rows, k) for k in range(rows + 1)], dtype=float) / 2.0**rows


def check_counts(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> np.ndarray:
    """Counts as an int array of rows + 1 non-negative entries, else CountsError."""
    table = np.asarray(counts)
    if table.ndim != 1 or table.size != rows + 1:
        raise CountsError(
            f"counts must hold {rows + 1} bins (one per bin of a {rows}-row board), "
            f"got shape {table.shape}: {table.tolist()}"
        )
    if table.size and not np.all(np.isfinite(table.astype(float))):
        raise CountsError(f"counts must be finite integers, got {table.tolist()}")
    if np.any(table != np.round(table)) or np.any(table < 0):
        raise CountsError(f"counts must be non-negative integers, got {table.tolist()}")
    return table.astype(np.int64)


def expected_counts(settled: int, rows: int = ROWS) -> np.ndarray:
    """Expected balls per bin for ``settled`` balls: Binomial(rows, 1/2) pmf x settled."""
    if settled < 0:
        raise CountsError(f"settled balls must be >= 0, got {settled}")
    return bin_probabilities(rows) * settled


def _chi2_rows(tables: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """Pearson's statistic of each row of ``tables``; one formula for observed and simulated."""
    return np.asarray((((tables - expected) ** 2) / expected).sum(axis=-1), dtype=float)


def _settled_expected(table: np.ndarray, rows: int) -> np.ndarray:
    settled = int(table.sum())
    if settled == 0:
        raise NoSettledBallsError(
            "no ball settled in a bin (all counts are 0): chi-squared needs at least one "
            "settled ball"
        )
    return expected_counts(settled, rows)


def chi2_statistic(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> float:
    """The paper's statistic, sum over every bin of (O - E)^2 / E, for one table of counts."""
    table = check_counts(counts, rows)
    return float(_chi2_rows(table, _settled_expected(table, rows)))


def critical_value(alpha: float = ALPHA, dof: int = ROWS) -> float:
    """Chi-squared critical value (19.675 for 5 %, 11 d.o.f.; the paper rounds to 19.68)."""
    return float(sps.chi2.ppf(1.0 - alpha, dof))


def p_asymptotic(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> float:
    """The paper's test as a p-value: chi-squared tail with bins - 1 degrees of freedom."""
    return float(sps.chi2.sf(chi2_statistic(counts, rows), rows))


def null_statistics(settled: int, rows: int = ROWS, draws: int = DEFAULT_DRAWS,
                    seed: SeedLike = DEFAULT_SEED) -> np.ndarray:
    """Chi-squared of ``draws`` multinomial tables from a perfect board with ``settled`` balls."""
    if settled < 1:
        raise NoSettledBallsError(f"a null distribution needs >= 1 settled ball, got {settled}")
    if draws < 1:
        raise CountsError(f"Monte Carlo draws must be >= 1, got {draws}")
    rng = np.random.default_rng(seed)
    probabilities = bin_probabilities(rows)
    tables = rng.multinomial(settled, probabilities, size=draws)
    return _chi2_rows(tables, probabilities * settled)


def p_monte_carlo(counts: Sequence[int] | np.ndarray, rows: int = ROWS,
                  draws: int = DEFAULT_DRAWS, seed: SeedLike = DEFAULT_SEED) -> float:
    """Calibrated p-value: (k + 1) / (draws + 1), k = simulated tables with chi2 >= observed."""
    observed = chi2_statistic(counts, rows)
    simulated = null_statistics(int(np.sum(counts)), rows, draws, seed)
    threshold = observed - _TIE_TOLERANCE * max(1.0, observed)
    return float((np.count_nonzero(simulated >= threshold) + 1) / (draws + 1))


def paper_test_size(settled: int, rows: int = ROWS, alpha: float = ALPHA,
                    draws: int = DEFAULT_DRAWS, seed: SeedLike = DEFAULT_SEED) -> float:
    """How often the paper's asymptotic test rejects a perfect board at this ball count."""
    simulated = null_statistics(settled, rows, draws, seed)
    return float(np.mean(simulated > critical_value(alpha, rows)))


@dataclass(frozen=True, eq=False)
class PooledTails:
    """A table after merging sparse outer bins; ``groups`` lists the original bins per cell."""

    observed: np.ndarray
    expected: np.ndarray
    groups: tuple[tuple[int, ...], ...]

    @property
    def dof(self) -> int:
        """Degrees of freedom of the merged table: cells - 1."""
        return len(self.groups) - 1


def _merge(groups: list[list[int]], index: int) -> None:
    """Merge cell ``index`` with cell ``index + 1`` in place."""
    groups[index : index + 2] = [groups[index] + groups[index + 1]]


def _expected_of(groups: list[list[int]], expected: np.ndarray) -> np.ndarray:
    return np.array([expected[g].sum() for g in groups])


def _merge_tails(groups: list[list[int]], expected: np.ndarray, minimum: float) -> None:
    """Grow both outer cells inward until each holds >= minimum expected balls."""
    while len(groups) > 2:
        cells = _expected_of(groups, expected)
        if cells[0] >= minimum and cells[-1] >= minimum:
            return
        if cells[-1] < minimum:
            _merge(groups, len(groups) - 2)
        if cells[0] < minimum and len(groups) > 2:
            _merge(groups, 0)


def _merge_smallest(groups: list[list[int]], expected: np.ndarray, minimum: float) -> None:
    """For tiny samples: merge the sparsest inner cell with its smaller neighbour."""
    while len(groups) > 1:
        cells = _expected_of(groups, expected)
        i = int(np.argmin(cells))
        if cells[i] >= minimum:
            return
        left = cells[i - 1] if i > 0 else math.inf
        right = cells[i + 1] if i + 1 < len(cells) else math.inf
        _merge(groups, i - 1 if left <= right else i)


def pool_tails(counts: Sequence[int] | np.ndarray, rows: int = ROWS,
               min_expected: float = MIN_EXPECTED) -> PooledTails:
    """Merge outer bins symmetrically until every cell expects >= ``min_expected`` balls."""
    table = check_counts(counts, rows)
    expected = _settled_expected(table, rows)
    groups = [[k] for k in range(rows + 1)]
    _merge_tails(groups, expected, min_expected)
    _merge_smallest(groups, expected, min_expected)
    return PooledTails(
        observed=np.array([table[g].sum() for g in groups]),
        expected=_expected_of(groups, expected),
        groups=tuple(tuple(g) for g in groups),
    )


def p_pooled_tails(counts: Sequence[int] | np.ndarray, rows: int = ROWS,
                   min_expected: float = MIN_EXPECTED) -> float:
    """Asymptotic p-value after merging sparse tails, where the approximation holds."""
    return _pooled_tails_p(pool_tails(counts, rows, min_expected), min_expected)


def _pooled_tails_p(pooled: PooledTails, min_expected: float = MIN_EXPECTED) -> float:
    """Chi-squared tail of the merged table; at least two cells are needed."""
    if pooled.dof < 1:
        raise TooFewBallsError(
            f"{int(pooled.observed.sum())} settled balls cannot fill two cells of expected "
            f"count >= {min_expected}; the merged test needs about {2 * min_expected:.0f}+ balls"
        )
    statistic = float(_chi2_rows(pooled.observed, pooled.expected))
    return float(sps.chi2.sf(statistic, pooled.dof))


@dataclass(frozen=True)
class GoodnessOfFit:
    """Every statistic of one table of counts (one trial's, or a sum over repetitions)."""

    counts: tuple[int, ...]
    settled: int
    chi2: float
    dof: int
    p_asymptotic: float
    p_monte_carlo: float
    p_pooled_tails: float | None
    pooled_tails_dof: int | None
    effect_size: float  # Cohen's w, bias-corrected: how far from the binomial (effect_size)
    detectable_effect: float  # the w this many balls detect half the time at 5 %


def goodness_of_fit(counts: Sequence[int] | np.ndarray, rows: int = ROWS,
                    draws: int = DEFAULT_DRAWS, seed: SeedLike = DEFAULT_SEED) -> GoodnessOfFit:
    """Test one table: the paper's chi2 and p, the Monte Carlo p and the pooled-tails p."""
    table = check_counts(counts, rows)
    pooled = pool_tails(table, rows)
    tails_p, tails_dof = (None, None) if pooled.dof < 1 else (_pooled_tails_p(pooled), pooled.dof)
    return GoodnessOfFit(
        counts=tuple(int(c) for c in table),
        settled=int(table.sum()),
        chi2=chi2_statistic(table, rows),
        dof=rows,
        p_asymptotic=p_asymptotic(table, rows),
        p_monte_carlo=p_monte_carlo(table, rows, draws, seed),
        p_pooled_tails=tails_p,
        pooled_tails_dof=tails_dof,
        effect_size=effect_size(table, rows),
        detectable_effect=detectable_effect(int(table.sum()), rows),
    )


def effect_size(counts: Sequence[int] | np.ndarray, rows: int = ROWS) -> float:
    """How far the counts' law is from the binomial, whatever the number of balls.

    Cohen's w, sqrt(sum (q - p)^2 / p) over the bins, estimated without its sampling bias as
    sqrt(max(0, chi2 - dof) / N): a test's p falls as balls are added, w does not, so runs of
    different sizes and seeds compare. A perfect board gives about 0.
    """
    table = check_counts(counts, rows)
    settled = int(table.sum())
    if settled < 1:
        raise NoSettledBallsError("an effect size needs >= 1 settled ball")
    return math.sqrt(max(0.0, chi2_statistic(table, rows) - rows) / settled)


def detectable_effect(settled: int, rows: int = ROWS, alpha: float = ALPHA,
                      power: float = 0.5) -> float:
    """The effect size w that the chi-squared test at ``alpha`` rejects with this ``power``
    for ``settled`` balls (noncentral chi-squared with noncentrality N w^2).

    A board whose w is near this value passes or fails with the seed: half the time at the
    default power of 0.5.
    """
    if settled < 1:
        raise NoSettledBallsError(f"a detectable effect needs >= 1 ball, got {settled}")
    if not 0 < alpha < 1 or not alpha < power < 1:
        raise CountsError(f"need 0 < alpha < power < 1, got alpha {alpha}, power {power}")
    critical = critical_value(alpha, rows)
    noncentrality = brentq(lambda lam: sps.ncx2.sf(critical, rows, lam) - power, 1e-9, 1e4)
    return math.sqrt(noncentrality / settled)


def pass_rate(counts: Sequence[int] | np.ndarray, settled: int, rows: int = ROWS,
              alpha: float = ALPHA, draws: int = DEFAULT_DRAWS,
              seed: SeedLike = DEFAULT_SEED) -> float:
    """How often a run of ``settled`` balls passes the test at ``alpha`` if the board's law is
    the one these ``counts`` show (pooled over many runs).

    It is what a pass rate over seeds should be when the seeds only resample one law: an
    observed rate far from it means the seed changes the law itself. The law is the counts'
    shares shrunk towards the binomial until their w is the bias-corrected ``effect_size``
    (sampling noise in the counts would otherwise count as departure), and the runs are
    ``draws`` seeded multinomial tables, judged against the Monte Carlo null's critical
    value. Simulated, not read from the noncentral chi-squared: at a given w, how often a law
    passes also depends on where it departs (tails or shoulders), by a few percent.
    """
    table = check_counts(counts, rows)
    if settled < 1:
        raise NoSettledBallsError(f"a pass rate needs runs of >= 1 ball, got {settled}")
    if not 0 < alpha < 1:
        raise CountsError(f"need 0 < alpha < 1, got alpha {alpha}")
    rng = np.random.default_rng(seed)
    law = _denoised_law(table, rows)
    expected = bin_probabilities(rows) * settled
    critical = np.quantile(null_statistics(settled, rows, draws, rng), 1 - alpha)
    runs = rng.multinomial(settled, law, size=draws)
    return float(np.mean(_chi2_rows(runs, expected) <= critical))


def _denoised_law(table: np.ndarray, rows: int) -> np.ndarray:
    """The table's shares moved towards the binomial so that their w is ``effect_size``."""
    binomial = bin_probabilities(rows)
    corrected = effect_size(table, rows)  # raises first if no ball settled
    raw = math.sqrt(chi2_statistic(table, rows) / table.sum())
    if raw == 0:
        return binomial
    shares = table / table.sum()
    return np.asarray(binomial + (shares - binomial) * (corrected / raw), dtype=float)


def sum_over_repetitions(tables: Sequence[Sequence[int] | np.ndarray],
                         rows: int = ROWS) -> np.ndarray:
    """Bin-wise sum of several trials' counts (the pooled table)."""
    if len(tables) == 0:
        raise NoSettledBallsError("no trials to pool: pass at least one table of counts")
    return np.asarray(np.sum([check_counts(t, rows) for t in tables], axis=0), dtype=np.int64)


def pooled_over_repetitions(tables: Sequence[Sequence[int] | np.ndarray], rows: int = ROWS,
                            draws: int = DEFAULT_DRAWS,
                            seed: SeedLike = DEFAULT_SEED) -> GoodnessOfFit:
    """Test the SUM of the repetitions' counts: many trials give the power one trial lacks."""
    return goodness_of_fit(sum_over_repetitions(tables, rows), rows, draws, seed)
