"""A sense of normality: the world rolls a ball as the robot expects, and compare's anomaly
score says when reality stops doing so.

Two worlds in one daemon: the live world is the robot's internal model; a fork of it,
"reality", plays the real world. A ball rolls across the floor in both. Every cycle (50 ms)
both are stepped, the "camera" sees reality's ball on the floor (its x and y with seeded
noise, sigma 3 mm each), and the model compares that observation with its own ball: the
score stays near 1. Then a hand moves the real ball 10 cm sideways: the next score spikes
far above 3. The model takes that observation (``correct``) and the score falls back.

Starts its own daemon unless --connect is given:
python examples/normality.py [--engine mujoco|pybullet] [--seed N]
                             [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np

from galton.client import Client, EmbeddedDaemon, plane, spheres

CYCLE_S = 0.05
CYCLES = 30
PUSH_AT = 20  # the cycle at which a hand moves the real ball
PUSH = np.array([0.0, 0.1, 0.0])  # m
NOISE_M = 0.003  # the camera's noise on each horizontal axis
SIGMA_M = NOISE_M * np.sqrt(2)  # the noise's RMS distance: a score of about 1
THRESHOLD = 3.0  # docs/protocol.md, "compare": a conservative "not what I expected"


@dataclass(frozen=True)
class NormalityRun:
    """The anomaly score of each cycle, and where the hand moved the ball."""

    scores: np.ndarray
    push_at: int

    @property
    def before(self) -> np.ndarray:
        return self.scores[: self.push_at]


def observe(reality: Client, rng: np.random.Generator) -> np.ndarray:
    """The real ball's pose as a camera sees it on the floor: x and y with seeded noise."""
    pose = reality.get_states(["ball"]).poses.copy()
    pose[:, :2] += rng.normal(0.0, NOISE_M, (1, 2))
    return pose


def watch(sim: Client, seed: int) -> NormalityRun:
    rng = np.random.default_rng(seed)
    sim.reset("all")
    sim.spawn(plane())
    sim.spawn(spheres(["ball"], [[0, 0, 0.05]], 0.05))
    sim.set_states(["ball"], twists=np.array([[0.6, 0, 0, 0, 12.0, 0]]))  # rolling along x
    sim.fork_world("reality")
    reality = sim.world("reality")
    steps = round(CYCLE_S / sim.status().timestep)
    scores = np.zeros(CYCLES)
    try:
        for cycle in range(CYCLES):
            sim.step(steps)
            reality.step(steps)
            if cycle == PUSH_AT:
                moved = reality.get_states(["ball"]).poses
                moved[:, :3] += PUSH
                reality.set_states(["ball"], moved)
            seen = observe(reality, rng)
            scores[cycle] = sim.compare(["ball"], seen, sigma_position=SIGMA_M).score
            if scores[cycle] > THRESHOLD:  # not what it expected: take reality as it is
                sim.compare(["ball"], seen, sigma_position=SIGMA_M, correct=True)
    finally:
        sim.delete_world("reality")
    print(f"{sim.status().engine}: anomaly score before the push at most "
          f"{scores[:PUSH_AT].max():.2f} (mean {scores[:PUSH_AT].mean():.2f}); at the push "
          f"{scores[PUSH_AT]:.1f}; after correcting {scores[PUSH_AT + 1:].max():.2f}")
    return NormalityRun(scores, PUSH_AT)


def main(argv: list[str]) -> NormalityRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--seed", type=int, default=3)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=30.0) as sim:
            return watch(sim, args.seed)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as sim:
        return watch(sim, args.seed)


if __name__ == "__main__":
    main(sys.argv[1:])
