"""An occlusion: a ball rolls behind a box; the prediction keeps it until it reappears.

Two worlds in one daemon: the live world is the robot's model; a fork, "reality", plays the
real world. A ball rolls along x at 0.8 m/s; a box stands between the camera and the middle
of its path. Every cycle (50 ms) both worlds are stepped. While the camera sees the real
ball (x and y with seeded noise, sigma 2 mm) the model takes the sighting (``compare`` with
``correct``). At the first cycle it cannot, the model predicts one second ahead (``predict``,
one sample per cycle): each occluded cycle, the prediction is held against where the real
ball is. The program prints the largest error while hidden (the tests hold it under 1 cm)
and the cycle the prediction says the ball comes out against the one it does.

Starts its own daemon unless --connect is given:
python examples/occlusion.py [--engine mujoco|pybullet] [--seed N]
                             [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np

from galton.client import Client, EmbeddedDaemon, boxes, plane, spheres

RADIUS = 0.05
SPEED = 0.8  # m/s along x
START_X = -0.8
HIDDEN_HALF_X = 0.25  # the ball is out of sight while |x| is below this
CYCLE_S = 0.05
CYCLES = 40
HORIZON_S = 1.0
NOISE_M = 0.002


@dataclass(frozen=True)
class OcclusionRun:
    """The largest distance between the predicted and the real ball while hidden (m), the
    cycles it was hidden, and when the prediction said it comes out against when it did."""

    max_error: float
    hidden_cycles: int
    predicted_out: int
    out: int


def scene(sim: Client) -> None:
    sim.spawn(plane())
    sim.spawn(boxes(["screen"], [[0.0, -0.3, 0.2]], [HIDDEN_HALF_X - RADIUS, 0.02, 0.2],
                    static=True))
    sim.spawn(spheres(["ball"], [[START_X, 0, RADIUS]], RADIUS))
    sim.set_states(["ball"], twists=np.array([[SPEED, 0, 0, 0, SPEED / RADIUS, 0]]))


def hidden(x: float) -> bool:
    return abs(x) < HIDDEN_HALF_X


def track(sim: Client, seed: int) -> OcclusionRun:
    rng = np.random.default_rng(seed)
    sim.reset("all")
    scene(sim)
    sim.fork_world("reality")
    reality = sim.world("reality")
    steps = round(CYCLE_S / sim.status().timestep)
    predicted: np.ndarray | None = None
    errors: list[float] = []
    out = predicted_out = -1
    try:
        for cycle in range(CYCLES):
            sim.step(steps)
            reality.step(steps)
            real = reality.get_states(["ball"]).poses[0]
            if not hidden(real[0]):
                if predicted is not None and out < 0:
                    out = cycle
                seen = real.copy()
                seen[:2] += rng.normal(0.0, NOISE_M, 2)
                sim.compare(["ball"], seen[None], correct=True)
                continue
            if predicted is None:
                start = cycle
                found = sim.predict(HORIZON_S, every=CYCLE_S, read=["ball"])
                predicted = found.at("ball")
                later = [k for k, pose in enumerate(predicted) if k and not hidden(pose[0])]
                predicted_out = start + later[0] if later else -1
            errors.append(float(np.linalg.norm(predicted[cycle - start, :3] - real[:3])))
    finally:
        sim.delete_world("reality")
    found_run = OcclusionRun(max(errors), len(errors), predicted_out, out)
    print(f"{sim.status().engine}: hidden {found_run.hidden_cycles} cycles; the prediction "
          f"stayed within {found_run.max_error * 1e3:.1f} mm of the real ball; it said the "
          f"ball comes out at cycle {predicted_out}, it came out at cycle {out}")
    return found_run


def main(argv: list[str]) -> OcclusionRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=30.0) as sim:
            return track(sim, args.seed)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as sim:
        return track(sim, args.seed)


if __name__ == "__main__":
    main(sys.argv[1:])
