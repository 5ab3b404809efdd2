"""Physics that every engine must get right, checked through the bridge."""

from __future__ import annotations

import numpy as np
import pytest
from support import send_over_the_edge

from galton.client import Client, plane, spheres
from galton.client.laws import run_law
from galton.protocol import PhysicsError


@pytest.mark.parametrize("law", ["free-fall", "projectile"])
def test_free_flight_matches_the_law_suite(sim: Client, law: str) -> None:
    """The law suite's experiment (galton-client laws), within its tolerance g·t·dt."""
    for check in run_law(sim, law):
        assert check.passed, check


def test_a_slow_body_touching_nothing_keeps_coasting(sim: Client) -> None:
    """Only what is at rest may sleep: a ball drifting at 2 mm/s in zero gravity, touching
    nothing, keeps its speed (MuJoCo's island sleeping once froze it within 10 steps)."""
    speed = 0.002
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    sim.spawn(spheres(["drifter"], [[0, 0, 1]], 0.05,
                      twists=np.array([[speed, 0, 0, 0, 0, 0]])))
    stamp = sim.step(100)
    states = sim.get_states(["drifter"])
    assert states.twists[0, 0] == pytest.approx(speed, rel=1e-6)
    assert states.positions[0, 0] == pytest.approx(speed * stamp.sim_time, rel=1e-3)


def test_a_ball_dropped_on_a_plane_comes_to_rest_on_it(sim: Client) -> None:
    radius = 0.05
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], radius))
    sim.run_until(3.0)
    states = sim.get_states(["ball"])
    assert states.positions[0, 2] == pytest.approx(radius, abs=0.01)
    assert states.speeds[0] < 0.05


def test_divergence_is_a_typed_error_and_never_served_as_state(sim: Client) -> None:
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    send_over_the_edge(sim)
    with sim.telemetry(timeout=5), pytest.raises(PhysicsError, match="diverged"):
        sim.step(50)
    assert sim.status().faulted
    with pytest.raises(PhysicsError):
        sim.get_states(["ball"])
    with pytest.raises(PhysicsError):
        sim.step(1)
    sim.reset("state")
    assert np.isfinite(sim.get_states(["ball"]).poses).all()
