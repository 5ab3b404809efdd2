"""Physics before requests: a world playing at RTF 1.0 while many client processes hammer
the daemon with status and get_states, back to back.

Usage: python benchmarks/starvation.py [--engines mujoco,pybullet] [--clients 20]
           [--seconds 30] [--balls 100] [--json FILE]

The world: a plane and BALLS balls bouncing on it (restitution 0.9, so the contacts never
sleep). For each engine the script measures the RTF over ``--seconds`` of wall time alone,
then again while ``--clients`` processes (spawned, each with its own Zenoh session) call
status and get_states as fast as they are answered; it prints both RTFs and the requests
served. The issue's target: ≥ 0.95 under 20 clients.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import time
from typing import Any

import numpy as np
from common import ENGINES, daemon_client, machine, write_json

from galton.client import Client, plane, spheres

RTF = 1.0


def hammer(instance: str, endpoint: str, seconds: float,
           started: Any, counts: Any) -> None:
    """One client process: status and get_states back to back until the time is up."""
    with Client(instance, endpoint, timeout=30) as client:
        started.wait()
        deadline = time.monotonic() + seconds
        served = 0
        while time.monotonic() < deadline:
            client.status()
            client.get_states()  # every body, as a default get_states asks
            served += 2
        counts.put(served)


def rtf_over(sim: Client, seconds: float) -> float:
    """Sim seconds per wall second over ``seconds`` of playing (status at both ends)."""
    first, wall0 = sim.status().sim_time, time.monotonic()
    deadline = wall0 + seconds
    while time.monotonic() < deadline:
        remaining = deadline - time.monotonic()
        if remaining > 0:
            time.sleep(min(remaining, 0.5))  # a benchmark's wall clock, not a synchronisation
    return (sim.status().sim_time - first) / (time.monotonic() - wall0)


def build(sim: Client, balls: int) -> None:
    side = int(np.ceil(np.sqrt(balls)))
    names = [f"ball_{i}" for i in range(balls)]
    grid = np.column_stack([np.arange(balls) % side * 0.15, np.arange(balls) // side * 0.15,
                            np.full(balls, 0.5)])
    sim.spawn(plane(), spheres(names, grid, 0.05, restitution=0.9))


def measure(engine: str, clients: int, seconds: float, balls: int) -> dict[str, Any]:
    ctx = mp.get_context("spawn")
    with daemon_client(engine) as (daemon, sim):
        build(sim, balls)
        sim.play(rtf=RTF)
        alone = rtf_over(sim, seconds)
        started, counts = ctx.Event(), ctx.Queue()
        workers = [ctx.Process(target=hammer, args=(daemon.instance, daemon.endpoint,
                                                    seconds + 2, started, counts))
                   for _ in range(clients)]
        for worker in workers:
            worker.start()
        started.set()
        time.sleep(1.0)  # let every client get going before the window opens
        loaded = rtf_over(sim, seconds)
        served = sum(counts.get(timeout=seconds + 60) for _ in workers)
        for worker in workers:
            worker.join(timeout=30)
        sim.pause()
    return {"engine": engine, "clients": clients, "seconds": seconds, "balls": balls,
            "rtf_alone": alone, "rtf_loaded": loaded,
            "requests_per_s": served / (seconds + 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--json")
    args = parser.parse_args()
    rows = [measure(e, args.clients, args.seconds, args.balls) for e in args.engines.split(",")]
    print(f"# starvation on {machine()}: {args.clients} clients, {args.seconds:g} s, "
          f"{args.balls} balls playing at RTF {RTF}")
    print("| engine | RTF alone | RTF under load | requests served per s |")
    print("| --- | --- | --- | --- |")
    for row in rows:
        print(f"| {row['engine']} | {row['rtf_alone']:.3f} | {row['rtf_loaded']:.3f} | "
              f"{row['requests_per_s']:.0f} |")
    write_json(args.json, rows)


if __name__ == "__main__":
    main()
