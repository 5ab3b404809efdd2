"""The card's analytic reference for "fidelity after calibration": a box sliding to a stop
under Coulomb friction, a ball bouncing with a coefficient of restitution."""

from __future__ import annotations

import numpy as np
import pytest

from galton.client.report_card import calibrated as ref


def test_the_box_stops_where_coulomb_friction_says() -> None:
    stop = ref.SPEED ** 2 / (2 * ref.FRICTION * ref.GRAVITY)
    assert ref.box_x(10.0) == pytest.approx(stop)
    assert ref.box_x(0.1) == pytest.approx(0.15 - 0.5 * ref.FRICTION * ref.GRAVITY * 0.01)


def test_each_bounce_rises_e_squared_as_high() -> None:
    floor = ref.SLAB_TOP + ref.HALF
    drop = ref.BALL_START[2] - floor
    first = np.sqrt(2 * drop / ref.GRAVITY)
    rise = ref.RESTITUTION * ref.GRAVITY * first / ref.GRAVITY  # to the first apex
    assert ref.ball_z(first) == pytest.approx(floor)
    assert ref.ball_z(first + rise) - floor == pytest.approx(ref.RESTITUTION ** 2 * drop)
    names, times, poses, twists = ref.reference()
    assert names == ["box", "ball"] and poses.shape == (len(times), 2, 7)
    assert (poses[:, 1, 2] >= floor).all() and twists[0, 0] == ref.SPEED
