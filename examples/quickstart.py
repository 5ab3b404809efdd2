"""Drive a daemon with the SDK: a ground, ten balls, a second of physics, their heights.

Starts its own daemon on a free loopback port unless ENDPOINT is given:
python examples/quickstart.py [ENDPOINT INSTANCE]
"""

from __future__ import annotations

import sys

import numpy as np

from galton.client import Client, EmbeddedDaemon, plane, spheres


def drop_balls(sim: Client) -> np.ndarray:
    sim.reset("all")
    names = [f"ball_{i}" for i in range(10)]
    positions = [[0.3 * i, 0.0, 1.0 + 0.1 * i] for i in range(10)]
    sim.spawn(plane(), spheres(names, positions, radius=0.05, restitution=0.5))
    stamp = sim.run_until(1.0)
    heights = sim.get_states(names).positions[:, 2]
    print(f"{sim.status().engine}: t={stamp.sim_time:.3f} s, heights {np.round(heights, 3)}")
    return heights


def main(argv: list[str]) -> None:
    if argv:
        with Client(argv[1] if len(argv) > 1 else "galton", argv[0]) as sim:
            drop_balls(sim)
        return
    with EmbeddedDaemon("mujoco") as daemon, Client(daemon.instance, daemon.endpoint) as sim:
        drop_balls(sim)


if __name__ == "__main__":
    main(sys.argv[1:])
