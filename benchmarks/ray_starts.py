"""What the rule "a ray does not see the shape it starts in" costs PyBullet (issue 34).

Usage: python benchmarks/ray_starts.py [--rays 100000] [--repeats 3]

PyBullet's rays report nothing at all when they start inside a convex shape, so the engine
casts each ray that missed from within the primitives' bounding box once more, backwards
from its end, and looks up the start of a ray that then hits something (pybullet_rays.py).
Timed in process, on 200 static spheres over a plane: rays upwards from distinct origins
among the spheres (most miss: the worst case, one more batch), and a lidar's rays from one
origin among them. Printed: the median time of each with the rule and
with the extra cast switched off, and their ratio, measured within one run.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable

import numpy as np

from galton.client import plane, spheres
from galton.daemon.engines import pybullet_rays
from galton.daemon.engines.pybullet_engine import PybulletEngine


def median_seconds(call: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rays", type=int, default=100_000)
    parser.add_argument("--repeats", type=int, default=3)
    options = parser.parse_args()
    rng = np.random.default_rng(0)
    engine = PybulletEngine()
    centres = rng.uniform([-2, -2, 0.1], [2, 2, 0.5], (200, 3))
    engine.spawn([plane(), spheres([f"b{i}" for i in range(200)], centres, 0.05,
                                   static=True)])
    n = options.rays
    cases = {"from among the spheres, upwards, distinct origins": (
        rng.uniform([-2, -2, 0.1], [2, 2, 0.5], (n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1))),
        "lidar among the spheres, one origin": (np.tile([0.0, 0.0, 0.3], (n, 1)),
                                                rng.normal(size=(n, 3)))}
    leave = pybullet_rays._leave_primitives
    for name, (origins, directions) in cases.items():
        pybullet_rays._leave_primitives = leave
        with_rule = median_seconds(lambda o=origins, d=directions: engine.raycast(o, d, 100.0),
                                   options.repeats)
        pybullet_rays._leave_primitives = lambda bc, prims, rows, *rest: rows[:0]
        without = median_seconds(lambda o=origins, d=directions: engine.raycast(o, d, 100.0),
                                 options.repeats)
        print(f"{name}: {with_rule * 1e3:.0f} ms with the rule, {without * 1e3:.0f} ms "
              f"without, ratio {with_rule / without:.2f}")
    pybullet_rays._leave_primitives = leave
    engine.close()


if __name__ == "__main__":
    main()
