"""The drop-test bounce of the Galton board's materials on each engine, through the bridge.

docs/PHYSICS.md states the board's materials in physical terms; this test holds the engines
to them: a ball with the board's ball surface dropped on a plane with its floor surface (in
a world loaded with the board's settings) must rebound to e² of its drop height, e being the
documented coefficient of restitution. A fresh world's own defaults are
tests/test_neutral_world.py's.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from galton.analysis.board import BoardSpec
from galton.client import Client, plane, spheres

RADIUS = 0.045
DROP_HEIGHT = 0.5  # m between the ball's bottom and the plane
# Documented drop-test bounce of the paper board's materials (docs/PHYSICS.md), and its
# tolerance.
BOARD_BOUNCE = {"mujoco": 0.70, "pybullet": 0.72,
                "dart": 0.0,  # SDF's restitution 0
                "ode": 0.48}  # Webots' bounce 0.5
# Documented bounce of two of the board's balls meeting head-on at 1 m/s (MuJoCo: the
# moving bodies' own surface; PyBullet: the product of both, like any contact).
BOARD_BALL_BOUNCE = {"mujoco": 0.38, "pybullet": 0.73, "dart": 0.0, "ode": 0.49}
TOLERANCE = 0.05
WEBOTS_BOUNCE = 0.5  # the paper-webots board's contact, on every engine


def board_world(sim: Client, engine: str, board: str) -> dict[str, dict[str, Any]]:
    """A fresh world with the board's settings; the surfaces of its ball and floor."""
    contacts = BoardSpec.load(board).contacts[engine]
    sim.load_world(engine, dict(contacts.params) or None)
    return {role: {"friction": contacts.bodies[role].friction,
                   "restitution": contacts.bodies[role].restitution}
            for role in ("ball", "floor")}


def measured_bounce(sim: Client, surfaces: dict[str, dict[str, Any]]) -> float:
    """Drop, find the first rebound's apex, return sqrt(rebound height / drop height)."""
    sim.spawn(plane(**surfaces["floor"]),
              spheres(["ball"], [[0, 0, RADIUS + DROP_HEIGHT]], RADIUS, **surfaces["ball"]))
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


def ball_on_ball_bounce(sim: Client, surfaces: dict[str, dict[str, Any]],
                        speed: float = 1.0) -> float:
    """Two balls meet head-on in zero gravity: their separating over approaching speed."""
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    sim.spawn(spheres(["a", "b"], [[-0.2, 0, 1], [0.2, 0, 1]], RADIUS, mass=0.38,
                      twists=[[speed, 0, 0, 0, 0, 0], [-speed, 0, 0, 0, 0, 0]],
                      **surfaces["ball"]))
    sim.step(math.ceil(0.5 / sim.status().timestep))
    velocity = sim.get_states(["a", "b"]).twists[:, 0]
    return float((velocity[1] - velocity[0]) / (2 * speed))


def test_board_materials_bounce_as_documented(sim: Client, engine: str) -> None:
    surfaces = board_world(sim, engine, "paper")
    assert measured_bounce(sim, surfaces) == pytest.approx(BOARD_BOUNCE[engine],
                                                           abs=TOLERANCE)


def test_paper_webots_contact_bounces_half(sim: Client, engine: str) -> None:
    surfaces = board_world(sim, engine, "paper-webots")
    assert measured_bounce(sim, surfaces) == pytest.approx(WEBOTS_BOUNCE, abs=0.1)


def test_two_board_balls_bounce_off_each_other_as_documented(sim: Client,
                                                             engine: str) -> None:
    surfaces = board_world(sim, engine, "paper")
    assert ball_on_ball_bounce(sim, surfaces) == pytest.approx(BOARD_BALL_BOUNCE[engine],
                                                               abs=TOLERANCE)
