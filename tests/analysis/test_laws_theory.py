"""The law suite's closed forms against values known independently."""

from __future__ import annotations

import math

import numpy as np
import pytest

from galton.analysis import laws_theory as theory
from galton.analysis.laws import Check


def test_elliptic_k_matches_tabulated_values() -> None:
    assert theory.elliptic_k(0.0) == pytest.approx(math.pi / 2, rel=1e-15)
    assert theory.elliptic_k(math.sqrt(0.5)) == pytest.approx(1.8540746773013719, rel=1e-14)


def test_the_pendulum_period_grows_with_amplitude_as_the_series_says() -> None:
    small = 2 * math.pi * math.sqrt(0.26 / (1.0 * 9.81 * 0.5))
    for amplitude in (1e-4, 0.3):
        series = small * (1 + amplitude**2 / 16 + 11 * amplitude**4 / 3072)
        got = theory.pendulum_period(0.26, 1.0, 9.81, 0.5, amplitude)
        assert got == pytest.approx(series, rel=1e-5)
    assert theory.pendulum_period(0.26, 1.0, 9.81, 0.5, math.pi / 2) / small == \
        pytest.approx(1.18034, rel=1e-5)


def test_collisions_keep_momentum_and_part_at_e_times_the_approach() -> None:
    for e in (0.0, 0.5, 1.0):
        a, b = theory.collision_speeds(1.0, 2.0, 1.0, -0.5, e)
        assert 1.0 * a + 2.0 * b == pytest.approx(1.0 - 1.0)
        assert b - a == pytest.approx(e * 1.5)


def test_angular_momentum_turns_with_the_body() -> None:
    principal = theory.box_inertia(1.0, (0.05, 0.1, 0.2))
    assert principal == pytest.approx([0.05 / 3, 0.0425 / 3, 0.0125 / 3])
    turn = theory.quaternion_about((1, 1, 0), 0.7)
    matrix = theory.rotation_matrices(turn)[0]
    body_spin = np.array([0.1, 2.0, -0.3])
    momentum = theory.angular_momentum(principal, turn[None], (matrix @ body_spin)[None])[0]
    assert momentum == pytest.approx(matrix @ (principal * body_spin))
    assert theory.quaternion_product(turn, theory.quaternion_about((1, 1, 0), -0.7)) == \
        pytest.approx([0, 0, 0, 1])


def test_friction_laws() -> None:
    slope = math.radians(35)
    assert theory.sliding_acceleration(9.81, math.radians(20), 0.5) == 0.0
    assert theory.sliding_acceleration(9.81, slope, 0.5) == pytest.approx(
        9.81 * (math.sin(slope) - 0.5 * math.cos(slope)))
    assert theory.sliding_distance(2.0, 0.3, 9.81) == pytest.approx(4 / (2 * 0.3 * 9.81))
    assert theory.rolls_without_slipping(math.radians(20), 0.5, theory.SOLID_SPHERE)
    assert not theory.rolls_without_slipping(math.radians(60), 0.1, theory.SOLID_SPHERE)


def test_a_check_passes_within_its_tolerance_only() -> None:
    assert Check("x", "q", "m", 1.0, 1.04, 0.05, "why").passed
    assert not Check("x", "q", "m", 1.0, 1.06, 0.05, "why").passed
    assert not Check("x", "q", "m", 1.0, None, 0.05, "why").passed
    assert not Check("x", "q", "m", 1.0, math.nan, 0.05, "why").passed


def test_the_report_shows_unrun_checks_and_each_engines_own_tolerance() -> None:
    from galton.analysis.laws import EngineLaws, LawResults
    from galton.analysis.laws_report import render_law_report

    fine = EngineLaws("a", "1", 0.002, 9.81, [Check("fall", "drop", "m", 4.9, 4.91, 0.02, "w")])
    coarse = EngineLaws("b", "2", 0.004, 9.81, [
        Check("fall", "drop", "m", 4.9, 4.95, 0.04, "w"),
        Check("swing", "period", "s", 1.4, None, 0.01, "w", note="the engine loads no URDF")])
    text = render_law_report(LawResults([fine, coarse], {"laws": ["fall", "swing"]}))
    assert "| fall | drop | m | 4.9 | 4.91 (0.01) ±0.02 **pass** | 4.95 (0.05) ±0.04 **FAIL** |" \
        in text
    assert "| swing | period | s | 1.4 | not run | — (the engine loads no URDF) |" in text
    assert "- **b** 2: 0 of 2 checks pass" in text
