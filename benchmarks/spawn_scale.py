"""How spawn and delete scale: N spheres in one call, static and dynamic, through the bridge.

Usage: python benchmarks/spawn_scale.py [--engines mujoco,pybullet]
           [--counts 1000,2000,4000,8000,16000,100000] [--kinds static,dynamic]
           [--timeout 900] [--json FILE]

Each (engine, kind, count) runs in a fresh daemon, so every spawn builds its world from
nothing (no parked bodies from an earlier run): one spawn of N spheres 0.05 m in radius on a
grid 0.2 m apart, one step, then one delete of all N. Prints seconds per call; a call the
daemon refuses (a limit) or that passes ``--timeout`` is reported, not retried. Targets
(issue 23): cost linear in N; 10,000 in one spawn ≤ 2 s; 100,000 within 30 s.
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Callable

import numpy as np
from common import ENGINES, daemon_client, machine, write_json

from galton.client import spheres
from galton.protocol import GaltonError

KINDS = ("static", "dynamic")
RADIUS = 0.05
SPACING = 0.2


def grid(count: int) -> np.ndarray:
    """Sphere centres on a square grid at 1 m: none touches another."""
    side = math.ceil(math.sqrt(count))
    index = np.arange(count)
    return np.column_stack([index % side * SPACING, index // side * SPACING,
                            np.full(count, 1.0)])


def timed(call: Callable[[], object]) -> float | str:
    """Seconds the call took, or why it failed."""
    started = time.perf_counter()
    try:
        call()
    except GaltonError as exc:
        return f"{type(exc).__name__}: {str(exc)[:160]}"
    return time.perf_counter() - started


def measure(engine: str, kind: str, count: int, timeout: float) -> dict:
    names = [f"s{i}" for i in range(count)]
    group = spheres(names, grid(count), RADIUS, static=kind == "static")
    row: dict = {"engine": engine, "kind": kind, "count": count}
    with daemon_client(engine, timeout=timeout) as (_, sim):
        row["spawn_s"] = timed(lambda: sim.spawn(group, timeout=timeout))
        if isinstance(row["spawn_s"], float):
            row["step_s"] = timed(lambda: sim.step(1))
            row["delete_s"] = timed(lambda: sim.delete(names))
    return row


def cell(value: float | str | None) -> str:
    if value is None:
        return "-"
    return f"{value:.3f}" if isinstance(value, float) else value


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--counts", default="1000,2000,4000,8000,16000,100000")
    parser.add_argument("--kinds", default=",".join(KINDS))
    parser.add_argument("--timeout", type=float, default=900.0,
                        help="seconds the SDK waits for any one call")
    parser.add_argument("--json")
    args = parser.parse_args()
    counts = [int(c) for c in args.counts.split(",")]
    rows = []
    for engine in args.engines.split(","):
        for kind in args.kinds.split(","):
            for count in counts:
                rows.append(measure(engine, kind, count, args.timeout))
                print(rows[-1], flush=True)
    load = os.getloadavg()
    print(f"\n# spawn and delete of N spheres in one call, through the bridge, on {machine()}"
          f" (load average at the end {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f})")
    print("| engine | kind | N | spawn (s) | step (s) | delete (s) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in rows:
        print(f"| {r['engine']} | {r['kind']} | {r['count']} | {cell(r['spawn_s'])} | "
              f"{cell(r.get('step_s'))} | {cell(r.get('delete_s'))} |")
    write_json(args.json, {"machine": machine(), "load_average": load, "rows": rows})


if __name__ == "__main__":
    main()
