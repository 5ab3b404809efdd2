"""A wrench held for a duration lasts that many steps even when the clock is reset
(scope 'time') while it is held: its end moves with the step counter."""

from __future__ import annotations

import numpy as np

from galton.client import Client, spheres

FORCE = 10.0


def _speed_after_wrench(sim: Client, reset_time_midway: bool) -> float:
    sim.reset()
    sim.spawn(spheres(["ball"], [[0, 0, 100]], 0.05))
    sim.step(100)
    dt = sim.status().timestep
    sim.apply_wrench(["ball"], [[FORCE, 0, 0, 0, 0, 0]], duration=10 * dt)
    sim.step(5)
    if reset_time_midway:
        sim.reset("time")
    states = sim.step_and_read(20, ["ball"])
    return float(states.twists[0, 0])


def test_a_time_reset_does_not_stretch_a_held_wrench(sim: Client) -> None:
    try:
        plain = _speed_after_wrench(sim, reset_time_midway=False)
        reset = _speed_after_wrench(sim, reset_time_midway=True)
    finally:
        sim.reset()
    assert plain > 0
    np.testing.assert_allclose(reset, plain, rtol=1e-9)
