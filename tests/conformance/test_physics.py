"""Physics that every engine must get right, checked through the bridge."""

from __future__ import annotations

import numpy as np
import pytest
from support import send_over_the_edge

from galton.client import Client, plane, spheres
from galton.protocol import PhysicsError

GRAVITY = 9.81


def test_free_fall_matches_half_g_t_squared(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[0, 0, 10.0]], 0.05))
    dt = sim.status().timestep
    steps = round(1.0 / dt)
    stamp = sim.step(steps)
    z = sim.get_states(["ball"]).positions[0, 2]
    expected = 10.0 - 0.5 * GRAVITY * stamp.sim_time**2
    assert z == pytest.approx(expected, abs=0.01 * (10.0 - expected))


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
