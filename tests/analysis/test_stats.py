"""The chi-squared statistics: exact values, calibration under a perfect board, edge cases."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats as sps
from support import tilted_law

from galton.analysis import stats
from galton.analysis.errors import (
    AnalysisError,
    CountsError,
    NoSettledBallsError,
    TooFewBallsError,
)

ALPHA = 0.05
SEED = 20_240_601
# The 100-ball expected vector as reference-board.md prints it (3 significant figures).
REFERENCE_EXPECTED_100 = [0.049, 0.537, 2.69, 8.06, 16.1, 22.6, 22.6, 16.1, 8.06, 2.69, 0.537,
                          0.049]
PASCAL_11 = [math.comb(11, k) for k in range(12)]  # expected counts for 2048 balls, exactly


def test_expected_counts_match_reference_and_sum_to_settled() -> None:
    expected = stats.expected_counts(100)
    np.testing.assert_allclose(expected, REFERENCE_EXPECTED_100, rtol=0.01)
    np.testing.assert_allclose(expected, 100 * sps.binom.pmf(np.arange(12), 11, 0.5))
    assert expected.sum() == pytest.approx(100)
    assert stats.expected_counts(2048).tolist() == PASCAL_11


def test_statistic_on_a_hand_computed_table() -> None:
    # 2048 balls expect Pascal's row; move one ball from bin 1 to bin 0:
    # (2 - 1)^2 / 1 + (10 - 11)^2 / 11 = 12 / 11.
    counts = [2, 10, *PASCAL_11[2:]]
    assert stats.chi2_statistic(counts) == pytest.approx(12 / 11)
    assert stats.chi2_statistic(PASCAL_11) == 0.0


def test_one_ball_in_an_outer_bin_costs_about_18_5() -> None:
    base = [0, 1, 3, 8, 16, 22, 23, 16, 8, 3, 0, 0]
    shifted = [1, 1, 3, 8, 16, 22, 22, 16, 8, 3, 0, 0]
    e0, e6 = stats.expected_counts(100)[[0, 6]]
    gain = (1 - e0) ** 2 / e0 - e0 + ((22 - e6) ** 2 - (23 - e6) ** 2) / e6
    assert stats.chi2_statistic(shifted) - stats.chi2_statistic(base) == pytest.approx(gain)
    assert (1 - e0) ** 2 / e0 - e0 == pytest.approx(18.5, abs=0.05)


def test_statistic_and_p_agree_with_scipy_chisquare() -> None:
    counts = np.random.default_rng(SEED).multinomial(250, stats.bin_probabilities())
    reference = sps.chisquare(counts, stats.expected_counts(250))
    assert stats.chi2_statistic(counts) == pytest.approx(reference.statistic)
    assert stats.p_asymptotic(counts) == pytest.approx(reference.pvalue)


def test_critical_value_is_scipys_and_rounds_to_the_papers() -> None:
    assert stats.critical_value() == pytest.approx(sps.chi2.ppf(1 - ALPHA, 11))
    assert stats.critical_value() == pytest.approx(19.675, abs=5e-4)
    assert round(stats.critical_value(), 2) == 19.68


def test_monte_carlo_p_is_seeded_and_bounded() -> None:
    counts = [0, 1, 3, 8, 16, 22, 23, 16, 8, 3, 0, 0]
    first = stats.p_monte_carlo(counts, draws=2_000, seed=7)
    assert first == stats.p_monte_carlo(counts, draws=2_000, seed=7)
    assert first == stats.p_monte_carlo(counts, draws=2_000, seed=np.random.default_rng(7))
    assert 0.5 < first <= 1.0
    extreme = [100] + [0] * 11
    assert stats.p_monte_carlo(extreme, draws=2_000, seed=7) == pytest.approx(1 / 2_001)


def _rejections(tables: np.ndarray, rng: np.random.Generator) -> tuple[int, int]:
    """(Monte Carlo, asymptotic) rejections at ALPHA over the tables."""
    mc = sum(stats.p_monte_carlo(t, draws=1_000, seed=rng) <= ALPHA for t in tables)
    asymptotic = sum(stats.p_asymptotic(t) <= ALPHA for t in tables)
    return mc, asymptotic


def test_monte_carlo_is_calibrated_where_the_papers_test_is_not() -> None:
    samples, balls = 400, 100
    rng = np.random.default_rng(SEED)
    tables = rng.multinomial(balls, stats.bin_probabilities(), size=samples)
    mc, asymptotic = _rejections(tables, rng)
    low, high = sps.binom.ppf(0.001, samples, ALPHA), sps.binom.isf(0.001, samples, ALPHA)
    assert low <= mc <= high, f"Monte Carlo rejected {mc}/{samples}; band [{low}, {high}]"
    # The paper's asymptotic test rejects a perfect 100-ball board about 12 % of the time.
    assert asymptotic > high, f"asymptotic rejected only {asymptotic}/{samples}"
    assert asymptotic > mc


def test_paper_test_size_is_inflated_at_100_balls() -> None:
    assert 0.09 < stats.paper_test_size(100, draws=5_000, seed=SEED) < 0.15


@pytest.mark.parametrize("balls", [10, 20, 23, 100, 1_000])
def test_pooling_reaches_min_expected_and_keeps_totals(balls: int) -> None:
    counts = np.random.default_rng(balls).multinomial(balls, stats.bin_probabilities())
    pooled = stats.pool_tails(counts)
    assert pooled.expected.min() >= stats.MIN_EXPECTED
    assert pooled.observed.sum() == balls
    assert pooled.expected.sum() == pytest.approx(balls)
    assert [k for g in pooled.groups for k in g] == list(range(12))
    assert pooled.expected.tolist() == pytest.approx(pooled.expected[::-1].tolist())
    assert pooled.dof == len(pooled.groups) - 1 >= 1


def test_pooling_at_100_balls_merges_four_bins_each_side() -> None:
    pooled = stats.pool_tails([0, 1, 3, 8, 16, 22, 23, 16, 8, 3, 0, 0])
    assert pooled.groups == ((0, 1, 2, 3), (4,), (5,), (6,), (7,), (8, 9, 10, 11))
    assert pooled.observed.tolist() == [12, 16, 22, 23, 16, 11]
    assert pooled.dof == 5
    assert 0 < stats.p_pooled_tails([0, 1, 3, 8, 16, 22, 23, 16, 8, 3, 0, 0]) <= 1


def test_too_few_balls_for_the_pooled_test() -> None:
    counts = [0, 0, 0, 0, 1, 2, 1, 1, 0, 0, 0, 0]
    assert stats.pool_tails(counts).dof == 0
    with pytest.raises(TooFewBallsError, match="5 settled balls"):
        stats.p_pooled_tails(counts)
    fit = stats.goodness_of_fit(counts, draws=200)
    assert fit.p_pooled_tails is None and fit.pooled_tails_dof is None


def test_pooled_over_repetitions_tests_the_sum() -> None:
    rng = np.random.default_rng(SEED)
    tables = rng.multinomial(100, stats.bin_probabilities(), size=10)
    pooled = stats.pooled_over_repetitions(tables, draws=500, seed=1)
    assert pooled.counts == tuple(tables.sum(axis=0).tolist())
    assert pooled.settled == 1_000
    assert pooled.chi2 == pytest.approx(stats.chi2_statistic(tables.sum(axis=0)))


@pytest.mark.parametrize("function", [stats.chi2_statistic, stats.p_asymptotic,
                                      stats.p_monte_carlo, stats.pool_tails,
                                      stats.goodness_of_fit])
def test_no_settled_ball_is_a_typed_error(function: object) -> None:
    with pytest.raises(NoSettledBallsError, match="no ball settled"):
        function([0] * 12)  # type: ignore[operator]


@pytest.mark.parametrize("counts, message", [
    ([1] * 11, "must hold 12 bins"),
    ([1] * 13, "must hold 12 bins"),
    ([[1] * 12], "must hold 12 bins"),
    ([-1] + [1] * 11, "non-negative integers"),
    ([0.5] + [1] * 11, "non-negative integers"),
    ([math.nan] + [1] * 11, "finite"),
])
def test_bad_counts_are_a_typed_error(counts: list, message: str) -> None:
    with pytest.raises(CountsError, match=message):
        stats.chi2_statistic(counts)


def test_errors_share_one_root_and_other_boards_work() -> None:
    assert issubclass(CountsError, AnalysisError)
    assert issubclass(NoSettledBallsError, AnalysisError)
    with pytest.raises(AnalysisError):
        stats.sum_over_repetitions([])
    assert stats.chi2_statistic([1, 3, 3, 1], rows=3) == 0.0


def test_effect_size_is_near_zero_for_a_perfect_board_and_finds_a_known_tilt() -> None:
    rng = np.random.default_rng(5)
    perfect = rng.multinomial(100_000, stats.bin_probabilities())
    assert stats.effect_size(perfect) < 0.01
    tilted = rng.multinomial(100_000, tilted_law(0.05))
    assert stats.effect_size(tilted) == pytest.approx(0.05, abs=0.006)


def test_effect_size_does_not_grow_with_the_balls() -> None:
    law = tilted_law(0.04)
    sizes = [stats.effect_size(np.random.default_rng(n).multinomial(n, law))
             for n in (20_000, 80_000, 320_000)]
    assert max(sizes) - min(sizes) < 0.01


def test_detectable_effect_is_rejected_at_its_power() -> None:
    """At w = detectable_effect(5,000), the 5 % chi-squared test rejects about half of the
    tables: measured on 2,000 seeded multinomial draws."""
    w = stats.detectable_effect(5_000)
    assert stats.detectable_effect(20_000) == pytest.approx(w / 2)
    tables = np.random.default_rng(11).multinomial(5_000, tilted_law(w), size=2_000)
    expected = stats.expected_counts(5_000)
    chi2 = np.sum((tables - expected) ** 2 / expected, axis=1)
    assert np.mean(chi2 > stats.critical_value()) == pytest.approx(0.5, abs=0.05)


def _law_counts(w: float) -> np.ndarray:
    """A tilted law as the counts of ten million balls (its shares to seven digits)."""
    return np.round(10_000_000 * tilted_law(w)).astype(np.int64)


def test_pass_rate_of_a_binomial_board_is_one_minus_alpha() -> None:
    """Counts drawn from the binomial itself, whose chi-squared is below its degrees of
    freedom: their sampling noise is not taken for a departure, so runs pass 95 % of the
    time."""
    sampled = np.random.default_rng(14).multinomial(40_000, stats.bin_probabilities())
    assert stats.effect_size(sampled) == 0.0
    assert stats.pass_rate(sampled, 5_000) == pytest.approx(1 - stats.ALPHA, abs=0.01)


def test_pass_rate_follows_the_effect_size_and_the_run_size() -> None:
    """A tilted law passes about as often as the noncentral chi-squared says, and less
    often with more balls per run or a larger w."""
    law = _law_counts(0.03)
    predicted = sps.ncx2.cdf(stats.critical_value(), 11, 5_000 * 0.03**2)
    assert stats.pass_rate(law, 5_000) == pytest.approx(predicted, abs=0.06)
    assert stats.pass_rate(law, 20_000) < stats.pass_rate(law, 5_000) < stats.pass_rate(
        law, 1_000)
    assert stats.pass_rate(_law_counts(0.05), 5_000) < stats.pass_rate(law, 5_000)


def test_pass_rate_matches_runs_drawn_from_the_same_law() -> None:
    """Pooled counts of a narrow law predict the share of independent 5,000-ball runs of that
    law that pass (300 seeded runs, judged by the bench's Monte Carlo test)."""
    narrow = tilted_law(-0.04)
    pooled = np.random.default_rng(14).multinomial(200_000, narrow)
    runs = np.random.default_rng(15).multinomial(5_000, narrow, size=300)
    observed = np.mean([stats.p_monte_carlo(run, draws=2_000) > stats.ALPHA for run in runs])
    assert stats.pass_rate(pooled, 5_000) == pytest.approx(observed, abs=0.09)


def test_pass_rate_is_seeded_and_checks_its_arguments() -> None:
    law = _law_counts(0.03)
    assert stats.pass_rate(law, 5_000, seed=3) == stats.pass_rate(law, 5_000, seed=3)
    with pytest.raises(NoSettledBallsError):
        stats.pass_rate(law, 0)
    with pytest.raises(NoSettledBallsError, match="settled ball"):
        stats.pass_rate([0] * 12, 5_000)
    with pytest.raises(CountsError, match="alpha"):
        stats.pass_rate(law, 5_000, alpha=1.5)
    with pytest.raises(CountsError):
        stats.pass_rate([1, 2, 3], 5_000)


def test_detectable_effect_checks_its_arguments() -> None:
    with pytest.raises(CountsError, match="alpha"):
        stats.detectable_effect(5_000, power=0.01)
    with pytest.raises(NoSettledBallsError):
        stats.detectable_effect(0)
