"""A fresh world is neutral: each engine's own contact defaults let a body rest where it falls.

A robot's internal model holds boxes, tables and floors, not the Galton board's hard balls
on wood (issue 48): on a fresh daemon of every engine, with no parameter set, a dropped box
must come to rest flat where it fell, a stack of boxes must stand, and a ball must hardly
bounce (ODE: Webots' own bounce 0.5). The Galton board's lively materials travel with the
board (client/boards; tests/test_drop_calibration.py). Sim time runs flat out (run_until).
"""

from __future__ import annotations

import numpy as np
import pytest

from galton.client import Client, boxes, plane, spheres
from galton.client.sdk.values import States

BOX_HALF = 0.10  # m: a 20 cm cube
BOX_MASS = 1.0  # kg
BOX_DROP = 0.3  # m between the box's bottom and the plane
LANDING = float(np.sqrt(2 * BOX_DROP / 9.8))  # s after release
# Bar `neutral-world` (issue 48): within 1 s of landing, and over the second after.
MAX_SPEED = 0.002  # m/s
MAX_SPIN = 0.01  # rad/s
MAX_CREEP = 0.001  # m in the second after
MAX_DRIFT = 0.005  # m from where it was dropped
MAX_TILT = 0.01  # rad
BALL_RADIUS = 0.025  # m: a 5 cm ball
BALL_DROP = 1.0  # m between the ball's bottom and the plane
MAX_REBOUND = {"ode": 0.30}  # m: Webots' default bounce 0.5 (e² = 0.25 of the drop)
MAX_REBOUND_DEFAULT = 0.05
STACK = 3
STACK_TIME = 10.0  # s
MAX_SINK = 0.005  # m the top box may sink into the soft contacts below it


def tilt(states: States) -> np.ndarray:
    """Each body's angle between its z axis and the world's (rad)."""
    qx, qy = states.poses[:, 3], states.poses[:, 4]
    cos_tilt = 1.0 - 2.0 * (qx**2 + qy**2)
    return np.asarray(np.arccos(np.clip(cos_tilt, -1.0, 1.0)))


def spin(states: States) -> np.ndarray:
    return np.asarray(np.linalg.norm(states.twists[:, 3:], axis=1))


def test_a_dropped_box_rests_flat_where_it_fell(sim: Client, engine: str) -> None:
    sim.spawn(plane(), boxes(["box"], [[0.0, 0.0, BOX_HALF + BOX_DROP]], [BOX_HALF] * 3,
                             mass=BOX_MASS))
    rested = sim.run_until_and_read(LANDING + 1.0, ["box"])
    later = sim.run_until_and_read(LANDING + 2.0, ["box"])
    facts = {"speed": rested.speeds[0], "spin": spin(rested)[0],
             "creep": float(np.linalg.norm(later.positions[0] - rested.positions[0])),
             "drift": float(np.linalg.norm(later.positions[0, :2])),
             "tilt": tilt(later)[0], "spin_after": spin(later)[0]}
    assert facts["speed"] <= MAX_SPEED, facts
    assert facts["spin"] <= MAX_SPIN and facts["spin_after"] <= MAX_SPIN, facts
    assert facts["creep"] <= MAX_CREEP, facts
    assert facts["drift"] <= MAX_DRIFT, facts
    assert facts["tilt"] <= MAX_TILT, facts
    assert later.positions[0, 2] == pytest.approx(BOX_HALF, abs=MAX_SINK), facts


def test_a_dropped_ball_hardly_bounces(sim: Client, engine: str) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0.0, 0.0, BALL_RADIUS + BALL_DROP]], BALL_RADIUS))
    dt = sim.status().timestep
    chunk = max(1, round(0.005 / dt))
    landed, apex = False, 0.0
    for _ in range(round(1.5 / (chunk * dt))):
        state = sim.step_and_read(chunk, ["ball"])
        height = state.positions[0, 2] - BALL_RADIUS
        landed = landed or height < 0.01
        if landed:
            apex = max(apex, height)
    assert landed
    assert apex <= MAX_REBOUND.get(engine, MAX_REBOUND_DEFAULT), apex


def test_a_stack_of_three_boxes_stands(sim: Client, engine: str) -> None:
    names = [f"box{i}" for i in range(STACK)]
    heights = [BOX_HALF * (2 * i + 1) for i in range(STACK)]
    sim.spawn(plane(), boxes(names, [[0.0, 0.0, z] for z in heights], [BOX_HALF] * 3,
                             mass=BOX_MASS))
    end = sim.run_until_and_read(STACK_TIME, names)
    drift = np.linalg.norm(end.positions[:, :2], axis=1)
    sink = np.asarray(heights) - end.positions[:, 2]
    facts = {"drift": drift.tolist(), "sink": sink.tolist(), "tilt": tilt(end).tolist(),
             "speed": end.speeds.tolist()}
    assert drift.max() <= MAX_DRIFT, facts
    assert sink.max() <= 2 * MAX_SINK, facts
    assert tilt(end).max() <= MAX_TILT, facts
    assert end.speeds.max() <= MAX_SPEED, facts
