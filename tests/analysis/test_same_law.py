"""``same_law.homogeneity``: whether two count tables share a law, as the seed table uses it
to test each engine's pooled balls against the exact lone ball's."""

from __future__ import annotations

import numpy as np
import pytest
from support import tilted_law

from galton.analysis import CountsError, TooFewBallsError, homogeneity, stats
from galton.analysis.same_law import merge_tails


def _draw(law: np.ndarray, balls: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).multinomial(balls, law)


def test_merge_tails_sums_each_side_and_keeps_every_ball() -> None:
    table = np.arange(12)
    merged = merge_tails(table, 2)
    assert merged.tolist() == [1, 2, 3, 4, 5, 6, 7, 8, 9, 21]
    assert merged.sum() == table.sum()


def test_samples_of_one_law_agree_at_the_test_size() -> None:
    """Under one law the p-values are uniform: about 5 % of seeded pairs fall below 0.05."""
    law = tilted_law(0.05)
    ps = [homogeneity(_draw(law, 20_000, seed), _draw(law, 5_000, seed + 1000)).p_value
          for seed in range(200)]
    assert 0.01 <= np.mean(np.array(ps) < stats.ALPHA) <= 0.10
    assert homogeneity(_draw(law, 20_000, 1), _draw(law, 5_000, 2)).dof == 9


def test_a_flat_law_is_told_from_the_binomial_with_enough_balls() -> None:
    flat, binomial = tilted_law(0.05), stats.bin_probabilities()
    result = homogeneity(_draw(flat, 95_000, 3), _draw(binomial, 95_000, 4))
    assert result.p_value < 1e-6
    assert result.chi2 > 50


def test_bad_tables_are_rejected_with_what_was_wrong() -> None:
    with pytest.raises(CountsError, match="12 bins"):
        homogeneity([1] * 11, [1] * 12)
    with pytest.raises(TooFewBallsError, match="counts_b holds no ball"):
        homogeneity([5] * 12, [0] * 12)
    with pytest.raises(TooFewBallsError, match="empty in both"):
        homogeneity([5] * 5 + [0] + [5] * 6, [3] * 5 + [0] + [3] * 6)
    with pytest.raises(CountsError, match="tail_bins"):
        homogeneity([5] * 12, [5] * 12, tail_bins=6)
