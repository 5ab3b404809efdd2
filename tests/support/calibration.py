"""calibrate's scenes: a box sliding and a ball bouncing on a heavy slab, whose surface lets
each body's own friction and restitution decide its contacts on that engine (MuJoCo takes
the larger friction and averages solref, ODE takes the larger, PyBullet and DART multiply:
docs/PHYSICS.md, "Calibration")."""

from __future__ import annotations

import numpy as np

from galton.client import Client, boxes, plane, spheres

# The slab's (friction, restitution) per engine.
SURFACE = {"mujoco": (0.0, 0.5), "pybullet": (1.0, 1.0), "dart": (1.0, 1.0), "ode": (0.0, 0.0)}
BOX_SPEED = 1.5  # m/s along x
SETTLE_S = 0.5  # the bodies settle on the slab (its contact quiet) before the box is pushed


def slide_and_bounce(sim: Client, engine: str, friction: float, restitution: float,
                     ball: bool = True) -> list[str]:
    """Spawn the scene, let it settle, push the box; return the moving bodies."""
    slab_friction, slab_restitution = SURFACE[engine]
    sim.spawn(plane())
    sim.spawn(boxes(["slab"], [[0.5, 0.0, 0.05]], [1.5, 0.6, 0.05], mass=500.0,
                    friction=slab_friction, restitution=slab_restitution))
    sim.spawn(boxes(["box"], [[0.0, -0.3, 0.15]], [0.05, 0.05, 0.05], mass=1.0,
                    friction=friction))
    moving = ["box"]
    if ball:
        sim.spawn(spheres(["ball"], [[0.5, 0.3, 3.0]], 0.05, mass=0.2,
                          restitution=restitution))
        moving.append("ball")
    sim.step(round(SETTLE_S / sim.status().timestep))
    states = sim.get_states(["box"])
    twist = np.zeros((1, 6))
    twist[0, 0] = BOX_SPEED
    sim.set_states(["box"], states.poses, twist)
    return moving
