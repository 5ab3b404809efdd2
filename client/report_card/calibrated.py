"""The report card's "fidelity after calibration" (issue 53): how close an engine gets to a
reference behaviour once its parameters are fitted, the paper's question asked fairly.

The reference is analytic, so no engine is its own judge: a box pushed at 1.5 m/s slides
to a stop under Coulomb friction μ = 0.3 (x = v₀t − ½μgt²), and a ball dropped from rest
bounces with a coefficient of restitution e = 0.5 (each flight a parabola, each rebound
speed e times the impact's). Each engine's scene puts them on a heavy slab whose surface
lets the bodies' own values decide their contacts (docs/PHYSICS.md, "Calibration"). The
engine is given the reference's own values first (its error there: "with the reference's
values"), then ``calibrate`` fits the box's friction and the ball's restitution from
there, once per seed; the error after (mean distance over the bodies and 30 Hz samples, mm)
is the card's value, its interval over the seeds' fits."""

from __future__ import annotations

import math

import numpy as np

from galton.analysis import card_intervals
from galton.analysis.card_intervals import Measure
from galton.client.sdk.client import Client, body_group, plane, spheres

FRICTION, RESTITUTION = 0.3, 0.5
GRAVITY = 9.81
SPEED = 1.5  # m/s, the box's push along x
HORIZON_S, RATE_HZ = 0.9, 30.0
SLAB_TOP = 0.1  # m
HALF = 0.05  # the box's half size and the ball's radius
BOX_START = np.array([0.0, -0.3, SLAB_TOP + HALF])
BALL_START = np.array([0.5, 0.3, 0.6])
FIT = {"box.friction": (0.05, 1.5), "ball.restitution": (0.0, 0.95)}
MEASURES = ("reference_values_error_mm", "calibrated_error_mm")
# The slab's (friction, restitution) per engine: as in tests/support/calibration.py.
SURFACE = {"mujoco": (0.0, 0.5), "pybullet": (1.0, 1.0), "dart": (1.0, 1.0), "ode": (0.0, 0.0)}


def box_x(t: float) -> float:
    """The sliding box's travel at time t (at rest once friction has stopped it)."""
    stop = SPEED / (FRICTION * GRAVITY)
    t = min(t, stop)
    return SPEED * t - 0.5 * FRICTION * GRAVITY * t * t


def ball_z(t: float) -> float:
    """The bouncing ball's centre height at time t (restitution e at every impact)."""
    floor = SLAB_TOP + HALF
    height, speed, began = float(BALL_START[2]), 0.0, 0.0  # each flight: start height, speed up
    while True:
        # the time this flight meets the floor: height + v s - g s²/2 = floor
        flight = (speed + math.sqrt(speed * speed + 2 * GRAVITY * (height - floor))) / GRAVITY
        if t <= began + flight or flight < 1e-4:
            s = min(t - began, flight)
            return max(floor, float(height + speed * s - 0.5 * GRAVITY * s * s))
        impact = GRAVITY * flight - speed
        height, speed, began = floor, RESTITUTION * impact, began + flight


def reference() -> tuple[list[str], np.ndarray, np.ndarray, np.ndarray]:
    """The reference's names, times, poses (samples, 2, 7) and the first sample's twists."""
    times = np.arange(round(HORIZON_S * RATE_HZ) + 1) / RATE_HZ
    poses = np.zeros((len(times), 2, 7))
    poses[:, :, 6] = 1.0
    poses[:, 0, :3] = BOX_START
    poses[:, 0, 0] += [box_x(t) for t in times]
    poses[:, 1, :3] = BALL_START
    poses[:, 1, 2] = [ball_z(t) for t in times]
    twists = np.zeros((2, 6))
    twists[0, 0] = SPEED
    return ["box", "ball"], times, poses, twists


def scene(sim: Client, engine: str) -> None:
    """A fresh world: the slab, and the box and ball with the reference's values."""
    sim.load_world(engine)
    slab_friction, slab_restitution = SURFACE[engine]
    sim.spawn(plane())
    sim.spawn(body_group("box", (1.5, 0.6, 0.05), ["slab"], [[0.5, 0.0, 0.05]], mass=500.0,
                         friction=slab_friction, restitution=slab_restitution))
    sim.spawn(body_group("box", (HALF, HALF, HALF), ["box"], [BOX_START.tolist()], mass=1.0,
                         friction=FRICTION))
    sim.spawn(spheres(["ball"], [BALL_START.tolist()], HALF, mass=0.2, restitution=RESTITUTION))
    sim.step(round(0.5 / sim.status().timestep))  # the slab settled on the plane


def calibrated_fidelity(sim: Client, engine: str, seeds: int, predictions: int
                        ) -> dict[str, Measure | None]:
    """The error (mm) with the reference's values, and after ``seeds`` fits."""
    scene(sim, engine)
    names, times, poses, twists = reference()
    before: list[float] = []
    after: list[float] = []
    for seed in range(seeds):
        fit = sim.calibrate(FIT, names, times, poses, twists=twists,
                            max_predictions=predictions, seed=seed, timeout=120.0)
        before.append(1000.0 * fit.error_before)
        after.append(1000.0 * fit.error_after)
    return {"reference_values_error_mm": at_least_zero(card_intervals.mean_measure(before)),
            "calibrated_error_mm": at_least_zero(card_intervals.mean_measure(after))}


def at_least_zero(measure: Measure) -> Measure:
    """An error's t interval, cut at 0 (no error is negative)."""
    return Measure(measure.value, max(0.0, measure.low), measure.high, measure.n)
