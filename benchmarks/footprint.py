"""Footprint of a daemon: idle with the paper board loaded, and RSS per 1,000 balls.

Usage: python benchmarks/footprint.py [--idle-seconds 10] [--json FILE]

Idle: a fresh daemon, the paper board spawned, the world paused; CPU is measured over
``--idle-seconds`` from the daemon's own telemetry (10 Hz) and from the OS's CPU times
over the same window, RSS from the OS. Growth: RSS
after spawning 1,000 and 2,000 balls resting on a floor, per 1,000 balls.
Targets (issue 6): idle ≤ 150 MB RSS and ≤ 1 % of a core.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
import psutil
from common import ENGINES, daemon_client, machine, rss_mb, write_json

from galton.analysis.board import BoardSpec
from galton.client import Client, plane, spheres
from galton.client.bench.build import board_groups


def idle_cpu(sim: Client, seconds: float) -> float:
    """Mean CPU % the daemon reports over ``seconds`` of telemetry while paused."""
    samples = []
    with sim.telemetry(timeout=5) as stream:
        first = next(stream)
        for sample in stream:
            samples.append(sample.cpu_percent)
            if sample.wall_time - first.wall_time >= seconds:
                break
    return statistics.fmean(samples)


def balls_rss(sim: Client, daemon: object, count: int) -> float:
    sim.reset("all")
    sim.spawn(plane())
    if count == 0:
        sim.step(50)
        return rss_mb(daemon)  # type: ignore[arg-type]
    side = int(np.ceil(np.sqrt(count)))
    xy = np.array([(i % side * 0.12, i // side * 0.12) for i in range(count)])
    sim.spawn(spheres([f"b{i}" for i in range(count)],
                      np.column_stack([xy, np.full(count, 0.045)]), 0.045), timeout=120)
    sim.step(50)
    return rss_mb(daemon)  # type: ignore[arg-type]


def measure(engine: str, idle_seconds: float) -> dict:
    board = BoardSpec.load("paper")
    with daemon_client(engine) as (daemon, sim):
        sim.load_world(engine, board.engine_contacts(engine).params or None)  # its settings
        sim.spawn(*board_groups(board, engine))
        sim.step(10)
        idle_rss = rss_mb(daemon)
        process = psutil.Process(daemon.process.pid)  # type: ignore[union-attr]
        before, started = sum(process.cpu_times()[:2]), time.monotonic()
        cpu = idle_cpu(sim, idle_seconds)
        os_cpu = 100 * (sum(process.cpu_times()[:2]) - before) / (time.monotonic() - started)
        rss = {n: balls_rss(sim, daemon, n) for n in (0, 1000, 2000)}
    return {"engine": engine, "idle_rss_mb": idle_rss, "idle_cpu_percent": cpu,
            "idle_cpu_percent_os": os_cpu, "rss_mb_by_balls": rss,
            "rss_mb_per_1000_balls": (rss[2000] - rss[0]) / 2}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--idle-seconds", type=float, default=10.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(engine, args.idle_seconds) for engine in ENGINES]
    print(f"# daemon footprint on {machine()}")
    print("| engine | idle RSS, paper board (MB) | idle CPU (% of a core, telemetry / OS) | "
          "RSS per 1,000 balls (MB) |")
    print("| --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['idle_rss_mb']:.1f} | {r['idle_cpu_percent']:.2f} / "
              f"{r['idle_cpu_percent_os']:.2f} | {r['rss_mb_per_1000_balls']:.1f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
