"""RSS of a daemon over rounds of spawning and deleting 1,000 bodies, on each engine.

Usage: python benchmarks/memory_churn.py [--rounds 20] [--bodies 1000] [--json FILE]

Three ways of churning, each in a fresh daemon: delete by name with the world emptied,
delete by name with a static plane kept (so the world is never empty), and
reset(scope="spawned"). Prints RSS after the first and the last round, and the growth
per 1,000 bodies deleted over the second half of the rounds (after allocator warm-up:
0 means bounded).
"""

from __future__ import annotations

import argparse

import numpy as np
from common import ENGINES, daemon_client, machine, rss_mb, write_json

from galton.client import Client, plane, spheres

MODES = ("delete-empty", "delete-keep-plane", "reset-spawned")


def churn_round(sim: Client, mode: str, bodies: int) -> None:
    names = [f"churn_{i}" for i in range(bodies)]
    grid = np.column_stack([np.arange(bodies) % 40 * 0.2, np.arange(bodies) // 40 * 0.2,
                            np.full(bodies, 1.0)])
    sim.spawn(spheres(names, grid, 0.05), timeout=120)
    sim.step(10)
    if mode == "reset-spawned":
        sim.reset("spawned")
    else:
        sim.delete(names)


def measure(engine: str, mode: str, rounds: int, bodies: int) -> dict:
    with daemon_client(engine) as (daemon, sim):
        if mode == "delete-keep-plane":
            sim.spawn(plane())
        start = rss_mb(daemon)
        trace = []
        for _ in range(rounds):
            churn_round(sim, mode, bodies)
            trace.append(rss_mb(daemon))
    half = len(trace) // 2
    steady = (trace[-1] - trace[half]) / max(len(trace) - 1 - half, 1) * 1000 / bodies
    return {"engine": engine, "mode": mode, "start_mb": start, "first_round_mb": trace[0],
            "last_round_mb": trace[-1], "steady_growth_mb_per_1000_deleted": steady,
            "trace": trace}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=20)
    parser.add_argument("--bodies", type=int, default=1000)
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(e, m, args.rounds, args.bodies) for e in ENGINES for m in MODES]
    print(f"# memory churn on {machine()}: {args.rounds} rounds of {args.bodies} bodies")
    print("| engine | mode | RSS idle (MB) | after round 1 | after last | growth over the last "
          "half, MB per 1,000 deleted |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['mode']} | {r['start_mb']:.1f} | {r['first_round_mb']:.1f}"
              f" | {r['last_round_mb']:.1f} | {r['steady_growth_mb_per_1000_deleted']:.2f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
