"""Learning from surprise: a box's friction changes in reality, the model notices (its
anomaly score stays high), recalibrates from what it saw, and agrees with reality again.

Two worlds in one daemon: the live world is the robot's internal model; a fork of it,
"reality", plays the real world. Each episode a hand pushes a box across a table at
1.5 m/s in both; every 50 ms a camera sees reality's box (seeded noise of 1 mm a side) and
the model compares it with its own box (compare's ``trigger``: the daemon counts the
surprising comparisons in a row; a SurpriseWatch keeps the episode's observations, what a
calibration fits to). In episode 1 both agree. Before episode 2 reality's table is
polished: the box's friction falls from 0.8 to 0.3 and it slides further than the model
expects. The score stays above 3 for 4 cycles in a row: the daemon suggests a calibration
(the reply's ``suggested``, and a ``calibration_suggested`` event for any other listener),
the model calibrates the box's friction on the episode it saw (``calibrate`` with
``apply``), and in episode 3 its scores are low again.

Starts its own daemon unless --connect is given:
python examples/learn_from_surprise.py [--engine mujoco|pybullet] [--seed N]
                                       [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np

from galton.client import Client, EmbeddedDaemon, SurpriseWatch, boxes, plane

CYCLE_S = 0.05
CYCLES = 12  # an episode: 0.6 s, the box at rest before its end
MODEL_FRICTION, REAL_FRICTION = 0.8, 0.3
NOISE_M = 0.001
SIGMA_M = 0.005
THRESHOLD, WINDOW = 3.0, 4
PUSH = np.array([[1.5, 0.0, 0.0, 0.0, 0.0, 0.0]])  # the hand's push, m/s
# The table's surface, per engine, that lets the box's own friction decide their contact
# (docs/PHYSICS.md, "Calibration"): a heavy moving slab.
TABLE = {"mujoco": (0.0, 0.0), "pybullet": (1.0, 0.0)}


@dataclass(frozen=True)
class LearningRun:
    """Each episode's highest anomaly score, and what calibration fitted."""

    peaks: list[float]
    fitted: float
    predictions: int


def scene(sim: Client, engine: str) -> np.ndarray:
    """A table (a heavy slab) and a box resting on it; the box's start pose."""
    friction, restitution = TABLE[engine]
    sim.reset("all")
    sim.spawn(plane())
    sim.spawn(boxes(["table"], [[0.5, 0.0, 0.05]], [1.5, 0.6, 0.05], mass=500.0,
                    friction=friction, restitution=restitution))
    sim.spawn(boxes(["box"], [[0.0, 0.0, 0.15]], [0.05, 0.05, 0.05], mass=1.0,
                    friction=MODEL_FRICTION))
    sim.step(round(0.3 / sim.status().timestep))  # settled
    return sim.get_states(["box"]).poses


def episode(sim: Client, reality: Client, start: np.ndarray, watch: SurpriseWatch,
            rng: np.random.Generator) -> tuple[float, bool]:
    """Push the box in both worlds and watch; the peak score, and whether surprised."""
    for world in (sim, reality):
        world.set_states(["box"], start, PUSH)
    watch.start(sim.status().sim_time, ["box"], start)
    steps = round(CYCLE_S / sim.status().timestep)
    peak, surprised = 0.0, False
    for _ in range(CYCLES):
        sim.step(steps)
        reality.step(steps)
        seen = reality.get_states(["box"]).poses.copy()
        seen[:, :2] += rng.normal(0.0, NOISE_M, (1, 2))
        found = sim.compare(["box"], seen, sigma_position=SIGMA_M,
                            trigger=(THRESHOLD, WINDOW))
        peak = max(peak, found.score)
        watch.observe(found.sim_time, seen, found.score)
        surprised = found.suggested or surprised
    return peak, surprised


def learn(sim: Client, engine: str, seed: int) -> LearningRun:
    rng = np.random.default_rng(seed)
    start = scene(sim, engine)
    sim.fork_world("reality")
    reality = sim.world("reality")
    watch = SurpriseWatch(THRESHOLD, WINDOW)
    peaks, fitted, predictions = [], MODEL_FRICTION, 0
    try:
        for number in range(3):
            if number == 1:
                reality.update(["box"], friction=REAL_FRICTION)  # the table is polished
            peak, surprised = episode(sim, reality, start, watch, rng)
            peaks.append(peak)
            if surprised:
                names, times, poses = watch.observed()
                fit = sim.calibrate({"box.friction": (0.1, 1.0)}, names, times, poses,
                                    twists=PUSH, apply=True, max_predictions=100, seed=seed)
                fitted, predictions = fit.fitted["box.friction"], fit.predictions
    finally:
        sim.delete_world("reality")
    print(f"{sim.status().engine}: peak anomaly score per episode "
          f"{', '.join(f'{p:.1f}' for p in peaks)}; friction fitted {fitted:.3f} (reality "
          f"{REAL_FRICTION}) in {predictions} predictions")
    return LearningRun(peaks, fitted, predictions)


def main(argv: list[str]) -> LearningRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=tuple(TABLE))
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=60.0) as sim:
            return learn(sim, sim.status().engine, args.seed)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        return learn(sim, args.engine, args.seed)


if __name__ == "__main__":
    main(sys.argv[1:])
