"""Batch cost through the bridge: spawn N spheres in one call, read N states in one call.

Usage: python benchmarks/spawn_read.py [--bodies 1000] [--repeat 5] [--json FILE]

Each spawn goes into a world holding only a plane (the world is reset between spawns);
reads are of all N bodies. Target (issue 6): each ≤ 50 ms for 1,000 on both engines.
"""

from __future__ import annotations

import argparse
import statistics

import numpy as np
from common import ENGINES, daemon_client, machine, timed, write_json

from galton.client import Client, plane, spheres


def grid(count: int) -> np.ndarray:
    return np.column_stack([np.arange(count) % 40 * 0.2, np.arange(count) // 40 * 0.2,
                            np.full(count, 1.0)])


def spawn_once(sim: Client, names: list[str]) -> float:
    sim.reset("all")
    sim.spawn(plane())
    return timed(lambda: sim.spawn(spheres(names, grid(len(names)), 0.05), timeout=120), 1)[0]


def measure(engine: str, bodies: int, repeat: int) -> dict:
    names = [f"s{i}" for i in range(bodies)]
    with daemon_client(engine) as (_, sim):
        spawns = [spawn_once(sim, names) for _ in range(repeat)]
        sim.step(10)
        reads = timed(lambda: sim.get_states(names), repeat * 4)
        deletes = timed(lambda: sim.delete(names), 1)
    return {"engine": engine, "bodies": bodies, "spawn_s": spawns, "read_s": reads,
            "delete_s": deletes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(engine, args.bodies, args.repeat) for engine in ENGINES]
    print(f"# batch spawn and read through the bridge on {machine()}, {args.bodies} spheres")
    print("| engine | spawn median (ms) | read median (ms) | delete (ms) |")
    print("| --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {statistics.median(r['spawn_s']) * 1e3:.1f} | "
              f"{statistics.median(r['read_s']) * 1e3:.2f} | {r['delete_s'][0] * 1e3:.1f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
