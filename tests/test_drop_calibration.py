"""The drop-test bounce of each engine's default contact, measured through the bridge.

docs/PHYSICS.md states each engine's default contact in physical terms; this test holds the
engines to it: a ball dropped on a plane (both with the daemon's default settings) must
rebound to e² of its drop height, e being the documented coefficient of restitution.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from galton.client import Client, plane, spheres

RADIUS = 0.045
DROP_HEIGHT = 0.5  # m between the ball's bottom and the plane
# Documented drop-test bounce of the daemon defaults (docs/PHYSICS.md), and its tolerance.
DEFAULT_BOUNCE = {"mujoco": 0.70, "pybullet": 0.72,
                  "dart": 0.0,  # SDF's restitution 0
                  "ode": 0.48}  # Webots' bounce 0.5
# Documented bounce of two balls meeting head-on at 1 m/s with the defaults (MuJoCo: the
# moving bodies' own surface; PyBullet: the product of both, like any contact).
DEFAULT_BALL_BOUNCE = {"mujoco": 0.38, "pybullet": 0.73, "dart": 0.0, "ode": 0.49}
TOLERANCE = 0.05
# The paper-webots preset's contact: a Webots-like bounce of 0.5 on both engines.
WEBOTS_PARAMS = {"mujoco": {"default_restitution": 0.5, "default_static_restitution": 0.5},
                 "pybullet": {"default_restitution": 0.707,
                              "default_static_restitution": 0.707},
                 "dart": {"default_restitution": 0.707, "default_static_restitution": 0.707},
                 "ode": {"default_restitution": 0.5, "default_static_restitution": 0.5}}
WEBOTS_BOUNCE = 0.5


def measured_bounce(sim: Client) -> float:
    """Drop, find the first rebound's apex, return sqrt(rebound height / drop height)."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, RADIUS + DROP_HEIGHT]], RADIUS))
    dt = sim.status().timestep
    bounced, apex = False, 0.0
    for _ in range(math.ceil(2.0 / dt / 2)):
        sim.step(2)
        state = sim.get_states(["ball"])
        z, vz = state.positions[0, 2] - RADIUS, state.twists[0, 2]
        if not bounced and vz > 0:
            bounced = True
        if bounced:
            apex = max(apex, z)
            if vz < 0:
                break
    return float(np.sqrt(max(apex, 0.0) / DROP_HEIGHT))


def ball_on_ball_bounce(sim: Client, speed: float = 1.0) -> float:
    """Two balls meet head-on in zero gravity: their separating over approaching speed."""
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    sim.spawn(spheres(["a", "b"], [[-0.2, 0, 1], [0.2, 0, 1]], RADIUS, mass=0.38,
                      twists=[[speed, 0, 0, 0, 0, 0], [-speed, 0, 0, 0, 0, 0]]))
    sim.step(math.ceil(0.5 / sim.status().timestep))
    velocity = sim.get_states(["a", "b"]).twists[:, 0]
    return float((velocity[1] - velocity[0]) / (2 * speed))


def test_default_contact_bounces_as_documented(sim: Client, engine: str) -> None:
    assert measured_bounce(sim) == pytest.approx(DEFAULT_BOUNCE[engine], abs=TOLERANCE)


def test_paper_webots_contact_bounces_half(sim: Client, engine: str) -> None:
    sim.set_params(WEBOTS_PARAMS[engine])
    assert measured_bounce(sim) == pytest.approx(WEBOTS_BOUNCE, abs=0.1)


def test_two_balls_bounce_off_each_other_as_documented(sim: Client, engine: str) -> None:
    assert ball_on_ball_bounce(sim) == pytest.approx(DEFAULT_BALL_BOUNCE[engine],
                                                     abs=TOLERANCE)
