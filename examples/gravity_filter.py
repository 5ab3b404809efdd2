"""A gravity filter: noisy perceived poses of stacked boxes, corrected into the world and let
settle, end closer to the truth than the perception was.

A side world, "truth", holds a stack of three boxes at rest on the floor. A camera sees them
with seeded noise: 3 mm across, 12 mm in depth (the vertical, a camera looking down) and a
tilt of about 0.06 rad. The live world takes the perceived poses (``compare`` with
``correct``: the bodies are set to the observation, at rest) and is run until the boxes lie
still: boxes perceived floating fall, boxes perceived inside each other are pushed apart,
tilted ones lie flat. Gravity and contacts know heights and tilts, not where a box stands
across: the settled heights and tilts are far closer to the truth than the perceived ones
(the tests hold the height errors 50x smaller, the tilts 5x), positions as a whole closer
(what is left is the noise across, and the few mm a tilted box shifts as it lies down).

Starts its own daemon unless --connect is given:
python examples/gravity_filter.py [--engine mujoco|pybullet] [--seed N]
                                  [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

import numpy as np

from galton.client import Client, EmbeddedDaemon, boxes, plane

HALF = 0.05  # m, each box's half size
NAMES = ["box_0", "box_1", "box_2"]
NOISE_ACROSS_M = 0.002
NOISE_DEPTH_M = 0.015
NOISE_TILT_RAD = 0.06
SETTLE_S = 2.0
SETTLE_CHUNK_S = 0.01  # the quasi-static descent: this long a chunk, then at rest again
SETTLE_CHUNKS = 100
REST_SPEED = 0.002  # m/s


@dataclass(frozen=True)
class FilterRun:
    """Mean errors against the truth, perceived and settled: positions and heights (m),
    orientations (rad)."""

    perceived: Errors
    settled: Errors

    def factor(self, what: str) -> float:
        """How many times smaller the settled error is than the perceived one."""
        return float(getattr(self.perceived, what) / max(getattr(self.settled, what), 1e-9))


@dataclass(frozen=True)
class Errors:
    position: float
    height: float
    angle: float

    @classmethod
    def of(cls, truth: np.ndarray, poses: np.ndarray) -> Errors:
        position = np.linalg.norm(poses[:, :3] - truth[:, :3], axis=1)
        dots = np.abs(np.sum(poses[:, 3:] * truth[:, 3:], axis=1)).clip(0.0, 1.0)
        return cls(float(position.mean()), float(np.mean(np.abs(poses[:, 2] - truth[:, 2]))),
                   float(np.mean(2 * np.arccos(dots))))


def stack(sim: Client) -> None:
    sim.spawn(plane())
    sim.spawn(boxes(NAMES, [[0, 0, HALF * (2 * i + 1)] for i in range(3)], [HALF] * 3,
                    friction=0.8))


def tilt(rng: np.random.Generator) -> np.ndarray:
    """A small rotation about a random horizontal axis, as a quaternion (x y z w)."""
    axis = np.array([*rng.normal(size=2), 0.0])
    angle = rng.normal(0.0, NOISE_TILT_RAD)
    return np.array([*(axis / np.linalg.norm(axis) * np.sin(angle / 2)), np.cos(angle / 2)])


def perceive(truth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The true poses of boxes that stand upright, with the camera's noise."""
    seen = truth.copy()
    seen[:, :2] += rng.normal(0.0, NOISE_ACROSS_M, (len(truth), 2))
    seen[:, 2] += rng.normal(0.0, NOISE_DEPTH_M, len(truth))
    seen[:, 3:] = [tilt(rng) for _ in truth]
    return seen


def filter_stack(sim: Client, seed: int) -> FilterRun:
    rng = np.random.default_rng(seed)
    sim.reset("all")
    stack(sim)
    sim.create_world("truth")
    try:
        real = sim.world("truth")
        stack(real)
        truth = real.run_until_rest(SETTLE_S, NAMES, REST_SPEED, 0.05)[0].poses
    finally:
        sim.delete_world("truth")
    seen = perceive(truth, rng)
    sim.compare(NAMES, seen, np.zeros((3, 6)), correct=True)  # at rest where perceived
    settled = settle(sim)
    found = FilterRun(Errors.of(truth, seen), Errors.of(truth, settled))
    before, after = found.perceived, found.settled
    print(f"{sim.status().engine}: mean errors perceived -> settled: height "
          f"{before.height * 1e3:.1f} -> {after.height * 1e3:.2f} mm "
          f"({found.factor('height'):.0f}x), tilt {before.angle:.3f} -> {after.angle:.4f} rad "
          f"({found.factor('angle'):.0f}x), position {before.position * 1e3:.1f} -> "
          f"{after.position * 1e3:.1f} mm ({found.factor('position'):.1f}x)")
    return found


def settle(sim: Client) -> np.ndarray:
    """Let the boxes find their rest without the energy of the perception's overlaps: a few
    steps at a time, each followed by taking every speed away (a quasi-static descent), then
    a free run until they lie still."""
    steps = max(1, round(SETTLE_CHUNK_S / sim.status().timestep))
    still = np.zeros((len(NAMES), 6))
    for _ in range(SETTLE_CHUNKS):
        sim.step(steps)
        sim.set_states(NAMES, twists=still)
    now = sim.status().sim_time
    return sim.run_until_rest(now + SETTLE_S, NAMES, REST_SPEED, 0.05)[0].poses


def main(argv: list[str]) -> FilterRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=30.0) as sim:
            return filter_stack(sim, args.seed)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as sim:
        return filter_stack(sim, args.seed)


if __name__ == "__main__":
    main(sys.argv[1:])
