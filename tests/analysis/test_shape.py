"""Flatness of a bin distribution: exact on exact tables, calibrated on seeded binomial ones."""

from __future__ import annotations

import math

import numpy as np
import pytest

from galton.analysis import shape
from galton.analysis.errors import CountsError, NoSettledBallsError

PASCAL_11 = [math.comb(11, k) for k in range(12)]  # the binomial law exactly, 2048 balls


def pascal_centred(rows: int) -> list[int]:
    """The exact law of ``rows`` fair choices, centred on the 12 bins (rows even, < 11)."""
    offset = (11 - rows) // 2
    table = [0] * 12
    for k in range(rows + 1):
        table[offset + k] = math.comb(rows, k)
    return table


def test_the_exact_binomial_has_the_kurtosis_of_eleven_rows() -> None:
    kurtosis = shape.excess_kurtosis(PASCAL_11)
    assert kurtosis == pytest.approx(-2 / 11, abs=1e-12)
    assert shape.effective_rows(kurtosis) == pytest.approx(11)


@pytest.mark.parametrize("rows", [4, 6, 8, 10])
def test_the_width_of_an_exact_binomial_is_half_the_root_of_its_rows(rows: int) -> None:
    assert shape.width(pascal_centred(rows)) == pytest.approx(math.sqrt(rows) / 2, abs=1e-12)
    assert shape.width(PASCAL_11) == pytest.approx(math.sqrt(11) / 2, abs=1e-12)
    assert shape.width([0] * 5 + [7] + [0] * 6) == 0.0  # every ball in one bin


@pytest.mark.parametrize("rows", [4, 6, 8])
def test_fewer_independent_choices_read_back_as_fewer_rows(rows: int) -> None:
    kurtosis = shape.excess_kurtosis(pascal_centred(rows))
    assert kurtosis == pytest.approx(-2 / rows, abs=1e-12)
    assert shape.effective_rows(kurtosis) == pytest.approx(rows)


def test_a_peaked_law_has_no_finite_effective_rows() -> None:
    peaked = [0, 0, 1, 2, 5, 200, 200, 5, 2, 1, 0, 0]
    kurtosis = shape.excess_kurtosis(peaked)
    assert kurtosis > 0
    assert shape.effective_rows(kurtosis) == math.inf


def test_binomial_boards_fall_inside_the_null_range_about_95_percent_of_the_time() -> None:
    rng = np.random.default_rng(20_261_123)
    inside = 0
    trials = 200
    for _ in range(trials):
        table = rng.multinomial(5_000, np.array(PASCAL_11) / 2048)
        inside += not shape.flatness(table, draws=500, seed=rng).outside_null
    assert 0.90 * trials <= inside <= 0.99 * trials


def test_a_flat_law_of_six_rows_is_outside_the_null_range() -> None:
    rng = np.random.default_rng(7)
    six_rows = np.array(pascal_centred(6)) / 64
    table = rng.multinomial(20_000, six_rows)
    result = shape.flatness(table, seed=1)
    assert result.outside_null
    assert result.effective_rows == pytest.approx(6, rel=0.15)
    assert result.binomial_excess_kurtosis == pytest.approx(-2 / 11)


def test_bad_tables_are_refused() -> None:
    with pytest.raises(CountsError):
        shape.excess_kurtosis([1, 2, 3])
    with pytest.raises(NoSettledBallsError):
        shape.excess_kurtosis([0] * 11 + [1])
    with pytest.raises(NoSettledBallsError):
        shape.width([0] * 12)
