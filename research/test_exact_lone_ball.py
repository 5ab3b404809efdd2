"""The exact (event-driven) lone-ball model behind the engine-free reference
(docs/research/physics-notebook.md).

``research/exact_lone_ball.py`` follows a solid sphere between rigid impacts, so its law
is set by mechanics alone. These tests hold its pieces to textbook results: a bounce keeps
e of the normal speed, friction either stops the contact point's slip (a solid sphere then
rolls, v = omega r) or slides by mu times the normal impulse, a ball rolling off the top of
a cylinder leaves where cos(phi) = 10/17, and on the paper board every walk ends in its bin.
``research/exact_scan.py`` runs it over laws and seeds and pools what it stored.
"""

from __future__ import annotations

import dataclasses
import math

import exact_lone_ball
import exact_scan
import numpy as np
import pytest

from galton.analysis.board import BoardSpec
from galton.analysis.board_release import Perturbation, perturbation


@pytest.fixture(scope="module")
def exact():
    return exact_lone_ball


FLOOR = np.array([0.0, 1.0])
RADIUS = 0.045


def test_a_head_on_bounce_keeps_e_of_the_speed(exact):
    ball = exact.Ball(np.zeros(2), np.array([0.0, -3.0]), 0.0)
    leaving = exact.impact(ball, FLOOR, RADIUS, exact.Contact(0.7, 0.25, 0.2))
    assert leaving == pytest.approx(2.1)
    assert ball.v == pytest.approx([0.0, 2.1])
    assert ball.spin == 0.0


def test_below_the_threshold_a_contact_does_not_bounce(exact):
    ball = exact.Ball(np.zeros(2), np.array([0.0, -0.1]), 0.0)
    assert exact.impact(ball, FLOOR, RADIUS, exact.Contact(0.7, 0.25, 0.2)) == 0.0
    assert ball.v[1] == pytest.approx(0.0)


def test_enough_friction_leaves_a_solid_sphere_rolling(exact):
    """Slip stopped in one impact: v_x falls to 5/7 of itself and v = omega r."""
    ball = exact.Ball(np.zeros(2), np.array([1.4, -2.0]), 0.0)
    exact.impact(ball, FLOOR, RADIUS, exact.Contact(0.5, 1.0, 0.2))
    assert ball.v[0] == pytest.approx(1.0)
    assert ball.spin * RADIUS == pytest.approx(ball.v[0])


def test_too_little_friction_slides_by_mu_times_the_normal_impulse(exact):
    ball = exact.Ball(np.zeros(2), np.array([3.0, -2.0]), 0.0)
    exact.impact(ball, FLOOR, RADIUS, exact.Contact(0.5, 0.1, 0.2))
    normal_impulse = 1.5 * 2.0
    assert ball.v[0] == pytest.approx(3.0 - 0.1 * normal_impulse)
    assert ball.spin == pytest.approx(0.1 * normal_impulse * RADIUS / (0.4 * RADIUS ** 2))


@pytest.mark.parametrize("side", [1.0, -1.0])
def test_a_ball_rolls_off_a_pin_where_gravity_cannot_hold_it(exact, side):
    reach, centre = 0.145, np.array([0.0, 4.0])
    ball = exact.Ball(centre + reach * np.array([side * 1e-6, 1.0]), np.zeros(2), 0.0)
    exact.roll_off(ball, centre, reach, RADIUS)
    offset = (ball.p - centre) / np.linalg.norm(ball.p - centre)
    assert offset[1] == pytest.approx(10 / 17, abs=1e-6)
    assert math.copysign(1.0, offset[0]) == side
    assert np.linalg.norm(ball.v) == pytest.approx(math.sqrt(9.81 * reach * 10 / 17), rel=1e-5)
    assert ball.v @ offset == pytest.approx(0.0, abs=1e-9)  # leaves along the surface
    assert ball.v[1] < 0 and math.copysign(1.0, ball.v[0]) == side


def test_every_walk_on_the_paper_board_ends_in_its_bin(exact):
    board, shake = _stream(exact, 30)
    seen, impacts = exact.run(board, shake, exact.Contact(0.7, 0.25, 0.2))
    assert (seen.bins >= 0).all() and max(impacts) < exact.MAX_EVENTS
    summary = exact.walk_probe.summarise(seen, board, shake)
    assert summary["balls"] == 30 and summary["walk_bin_mismatch"] == 0
    assert sum(summary["bins"]["counts"]) == 30


def test_a_dead_board_sends_no_ball_far(exact):
    """With no bounce a ball rolls off each pin beside the one above: the walk is narrow."""
    board, shake = _stream(exact, 40)
    seen, _ = exact.run(board, shake, exact.Contact(0.0, 0.5, 0.2))
    lively, _ = exact.run(board, shake, exact.Contact(0.7, 0.25, 0.2))
    assert seen.bins.std() < lively.bins.std()


def _stream(exact, balls: int) -> tuple[BoardSpec, Perturbation]:
    board = exact.walk_probe.released("paper", balls)
    return board, perturbation(board, 0, 0, balls)


def test_a_speed_dependent_bounce_falls_linearly_between_1_and_3_m_s(exact):
    law = exact.Contact(0.72, 0.25, 0.2, restitution_at_3=0.52)
    assert law.bounce(1.0) == pytest.approx(0.72)
    assert law.bounce(2.0) == pytest.approx(0.62)
    assert law.bounce(3.0) == pytest.approx(0.52)
    assert law.bounce(0.1) == 0.0  # below the threshold
    assert law.bounce(20.0) == 0.0  # clipped, never negative


def test_johnsons_plastic_bounce_falls_as_the_speed_to_minus_a_quarter(exact):
    law = exact.Contact(0.78, 0.25, 0.2, plastic_exponent=0.25)
    assert law.bounce(1.0) == pytest.approx(0.78)
    assert law.bounce(16.0) == pytest.approx(0.39)  # 16 ** -1/4 = 1/2
    assert law.bounce(0.3) == pytest.approx(0.95)  # capped: no ball comes back faster
    assert law.bounce(0.1) == 0.0  # below the threshold


def test_a_capped_law_gives_no_more_than_its_engines_ceiling(exact):
    law = exact.Contact(0.78, 0.25, 0.2, plastic_exponent=0.25, cap=0.72)
    assert law.bounce(0.5) == pytest.approx(0.72)  # the law alone would give 0.93
    assert law.bounce(16.0) == pytest.approx(0.39)  # fast impacts are under the cap


def test_a_whole_speed_law_reads_the_balls_speed_but_the_threshold_its_approach(exact):
    normal = exact.Contact(0.78, 0.25, 0.2, plastic_exponent=0.25)
    whole = dataclasses.replace(normal, whole_speed=True)
    assert normal.bounce(1.0, speed=16.0) == pytest.approx(0.78)
    assert whole.bounce(1.0, speed=16.0) == pytest.approx(0.39)
    assert whole.bounce(0.1, speed=16.0) == 0.0  # a grazing touch does not bounce


@pytest.fixture(scope="module")
def scan():
    return exact_scan


def test_a_scan_trial_records_the_law_and_the_speeds_it_was_asked_at(scan):
    run = scan.one("paper", 12, 0, {"restitution": 0.78, "plastic_exponent": 0.25})
    assert run["contact"]["plastic_exponent"] == 0.25 and run["contact"]["friction"] == 0.25
    assert sum(run["bins"]["counts"]) == 12 and run["walk_bin_mismatch"] == 0
    speeds = [run["approach_speed_percentiles"][q] for q in ("10", "50", "90", "99")]
    assert 0.2 <= speeds[0] <= speeds[1] <= speeds[2] <= speeds[3]


def test_the_scan_summary_pools_a_laws_seeds(scan):
    binomial = [1, 11, 55, 165, 330, 462, 462, 330, 165, 55, 11, 1]
    runs = [{"bins": {"counts": binomial}, "caught": 0} for _ in range(2)]
    line = scan.summary_line("law", runs)
    assert "balls   4096" in line and "width 1.658" in line and "seeds passing 2/2" in line
    assert scan.law_key({"restitution": 0.72, "friction": 0.25, "plastic_exponent": None}) == \
        '{"restitution": 0.72}'
    assert scan.law_key({"restitution": 0.78, "cap": 0.95}) == '{"restitution": 0.78}'
    assert scan.law_key({"restitution": 0.78, "cap": 0.72}) == '{"cap": 0.72, "restitution": 0.78}'
    assert scan.seed_range("3-5") == [3, 4, 5] and scan.seed_range("0,7") == [0, 7]
