"""RSS of a daemon over many cycles of spawning, stepping and removing a few bodies.

Usage: python benchmarks/soak.py [--engines mujoco pybullet] [--cycles 10000] [--bodies 5]
                                 [--steps 10] [--json FILE]

Two soaks per engine, each in a fresh daemon: ``spawn-delete`` (a plane stays; each cycle
spawns a few balls, steps, deletes them by name) and ``reset-all`` (each cycle spawns a
plane and the balls, steps, resets with scope "all"). Prints RSS at the start, after the
warm-up (the first 10 % of cycles: the allocator's and the caches' first growth), at the
end, and the growth per 1,000 cycles after the warm-up and over the last half: 0 means
bounded. A leak of a few kB per cycle shows as a few MB per 1,000. (PyBullet's removeBody
keeps 0.9 kB per body until the engine rebuilds its world, every 5,000 bodies removed: its
spawn-delete RSS climbs in steps for the first few rebuilds, then stays.)
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
from common import ENGINES, daemon_client, machine, rss_mb, write_json

from galton.client import Client, plane, spheres

MODES = ("spawn-delete", "reset-all")
WARM_UP = 0.1  # share of the cycles before the growth is measured
SAMPLES = 100  # RSS readings per soak, evenly spaced


def ball_row(count: int) -> np.ndarray:
    """Balls in a row above the plane, apart, so that they fall and bounce."""
    return np.column_stack([np.arange(count) * 0.2, np.zeros(count), np.full(count, 0.3)])


def cycle_for(sim: Client, mode: str, bodies: int, steps: int) -> Callable[[], None]:
    """One cycle of the soak, on a world set up for it."""
    names = [f"soak_{i}" for i in range(bodies)]
    balls = spheres(names, ball_row(bodies), 0.05)
    if mode == "spawn-delete":
        sim.spawn(plane())

        def spawn_delete() -> None:
            sim.spawn(balls)
            sim.step(steps)
            sim.delete(names)
        return spawn_delete

    def reset_all() -> None:
        sim.spawn(plane(), balls)
        sim.step(steps)
        sim.reset("all")
    return reset_all


def soak(engine: str, mode: str, cycles: int, bodies: int, steps: int) -> dict:
    """RSS of a fresh daemon sampled over ``cycles`` cycles of one mode."""
    every = max(cycles // SAMPLES, 1)
    warm, half = max(int(cycles * WARM_UP), 1), max(cycles // 2, 1)
    with daemon_client(engine) as (daemon, sim):
        cycle = cycle_for(sim, mode, bodies, steps)
        trace = [(0, rss_mb(daemon))]
        started = time.perf_counter()
        for done in range(1, cycles + 1):
            cycle()
            if done % every == 0 or done in (warm, half, cycles):
                trace.append((done, rss_mb(daemon)))
        wall = time.perf_counter() - started
    at = dict(trace)
    return {"engine": engine, "mode": mode, "cycles": cycles, "bodies": bodies,
            "steps": steps, "start_mb": at[0], "warm_mb": at[warm], "end_mb": at[cycles],
            "growth_mb_per_1000": per_1000(at, warm, cycles),
            "last_half_growth_mb_per_1000": per_1000(at, half, cycles), "wall_s": wall,
            "trace": trace}


def per_1000(rss: dict[int, float], first: int, last: int) -> float:
    """RSS growth in MB per 1,000 cycles between two sampled cycles."""
    return (rss[last] - rss[first]) / max(last - first, 1) * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", nargs="+", choices=ENGINES, default=list(ENGINES))
    parser.add_argument("--cycles", type=int, default=10_000)
    parser.add_argument("--bodies", type=int, default=5, help="balls per cycle")
    parser.add_argument("--steps", type=int, default=10, help="steps per cycle")
    parser.add_argument("--json", help="write every result, RSS traces included, here")
    args = parser.parse_args()
    results = [soak(engine, mode, args.cycles, args.bodies, args.steps)
               for engine in args.engines for mode in MODES]
    print(f"# daemon RSS soak on {machine()}: {args.cycles} cycles of {args.bodies} balls, "
          f"{args.steps} steps")
    print(f"| engine | mode | RSS start (MB) | after warm-up ({WARM_UP:.0%}) | end | "
          "growth after warm-up, MB per 1,000 cycles | over the last half | wall (s) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['mode']} | {r['start_mb']:.1f} | {r['warm_mb']:.1f} | "
              f"{r['end_mb']:.1f} | {r['growth_mb_per_1000']:.3f} | "
              f"{r['last_half_growth_mb_per_1000']:.3f} | {r['wall_s']:.0f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
