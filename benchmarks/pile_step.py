"""What a settled pile costs per step, in-process: n balls of 1 kg heaped in a narrow bin.

Usage: python benchmarks/pile_step.py [--engines dart,pybullet,mujoco] [--counts 8,24,48]
           [--timestep 0.001]

The Galton board's expensive stage is its piles (docs/PERFORMANCE.md): every ball of a pile
is one island of touching bodies, which DART solves with its Dantzig LCP solver (direct,
exact) where MuJoCo and PyBullet iterate. Each engine settles the pile for 0.6 s, then the
next 100 steps are timed. Compare engines within one run: the machine's load moves all.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from common import machine

from galton.daemon.engines import create_engine
from galton.protocol import BodyGroup

BALL_RADIUS = 0.045
IDENTITY = [0.0, 0.0, 0.0, 1.0]


def scene(count: int) -> list[BodyGroup]:
    """A floor, a bin 0.4 × 0.24 m inside, and ``count`` balls stacked four by two."""
    walls = [BodyGroup("plane", (5.0, 5.0), ["floor"], np.array([[0, 0, 0, *IDENTITY]]),
                       static=True),
             BodyGroup("box", (0.05, 0.3, 1.0), ["left", "right"], np.array(
                 [[-0.25, 0, 1, *IDENTITY], [0.25, 0, 1, *IDENTITY]]), static=True),
             BodyGroup("box", (0.3, 0.05, 1.0), ["front", "back"], np.array(
                 [[0, -0.17, 1, *IDENTITY], [0, 0.17, 1, *IDENTITY]]), static=True)]
    k = np.arange(count)
    poses = np.column_stack([-0.15 + k % 4 * 0.1, -0.05 + k // 4 % 2 * 0.1,
                             0.1 + k // 8 * 0.1, np.tile(IDENTITY, (count, 1))])
    return [*walls, BodyGroup("sphere", (BALL_RADIUS,), [f"ball{i}" for i in k], poses,
                              mass=1.0)]


def step_ms(engine_name: str, count: int, timestep: float) -> float:
    engine = create_engine(engine_name)
    try:
        engine.set_params({"timestep": timestep})
        engine.spawn(scene(count))
        engine.step(round(0.6 / timestep))
        started = time.perf_counter()
        engine.step(100)
        return (time.perf_counter() - started) * 10.0
    finally:
        engine.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="dart,pybullet,mujoco")
    parser.add_argument("--counts", default="8,24,48")
    parser.add_argument("--timestep", type=float, default=0.001)
    args = parser.parse_args()
    counts = [int(c) for c in args.counts.split(",")]
    print(f"# ms per step of a settled pile, {args.timestep * 1000:g} ms steps, on {machine()}")
    print("| engine | " + " | ".join(f"{n} balls" for n in counts) + " |")
    print("| --- |" + " --- |" * len(counts))
    for name in args.engines.split(","):
        cells = [f"{step_ms(name, n, args.timestep):.2f}" for n in counts]
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
