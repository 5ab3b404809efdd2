"""The playing world's clock and each front's status under a perception load (issue 35,
item 9): a world of BALLS balls playing at RTF 1.0 while CLIENTS client processes render
and ray cast back to back over one front (Zenoh or ZeroMQ).

Usage: python benchmarks/perception_load.py [--engines mujoco,pybullet] [--clients 20]
           [--seconds 20] [--balls 300] [--fronts zenoh,zmq] [--json FILE]

For each engine and each loaded front it reports the RTF alone and under load (over the
whole window, and the lowest over any 1 s of it), the status round trip over Zenoh and over
ZeroMQ (p50, p99, and how many of them got no reply in 5 s), and the perception requests
served per second. Goals: RTF ≥ 0.95, every front answering.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import threading
import time
from typing import Any

import numpy as np
from common import ENGINES, daemon_client, machine, write_json
from starvation import build

from galton.client import Client
from galton.protocol import GaltonError

RTF = 1.0
CAMERA = {"eye": [3.0, -3.0, 2.0], "target": [1.0, 1.0, 0.3], "width": 160, "height": 120}
RAYS = 100
PROBE_PERIOD_S = 0.05
PROBE_TIMEOUT_S = 5.0


def perceive(instance: str, endpoint: str, seconds: float, started: Any, counts: Any) -> None:
    """One client process: a render and a ray cast, back to back, until the time is up."""
    origins = np.tile([1.0, 1.0, 2.0], (RAYS, 1))
    directions = np.column_stack([np.linspace(-0.5, 0.5, RAYS), np.zeros(RAYS),
                                  -np.ones(RAYS)])
    with Client(instance, endpoint, timeout=60) as client:
        started.wait()
        deadline = time.monotonic() + seconds
        served = 0
        while time.monotonic() < deadline:
            try:
                client.render(CAMERA)
                client.raycast(origins, directions, max_length=5.0)
            except GaltonError as error:  # reported, not fatal: the window goes on
                print(f"perception request failed: {error}", flush=True)
                time.sleep(0.1)
                continue
            served += 2
        counts.put(served)


class Prober(threading.Thread):
    """Status round trips over one client every PROBE_PERIOD_S; the clock from each."""

    def __init__(self, client: Client, stop: threading.Event) -> None:
        super().__init__(daemon=True)
        self.client, self.stop = client, stop
        self.waits: list[float] = []
        self.clock: list[tuple[float, float]] = []  # (wall, sim time)
        self.lost = 0

    def run(self) -> None:
        while not self.stop.is_set():
            started = time.monotonic()
            try:
                sim_time = self.client.status().sim_time
            except GaltonError:
                self.lost += 1
                continue
            now = time.monotonic()
            self.waits.append(now - started)
            self.clock.append((now, sim_time))
            self.stop.wait(max(0.0, PROBE_PERIOD_S - (now - started)))

    def latency(self) -> dict[str, float]:
        waits = np.array(self.waits or [np.nan]) * 1000
        return {"p50_ms": float(np.percentile(waits, 50)),
                "p99_ms": float(np.percentile(waits, 99)), "lost": self.lost,
                "answered": len(self.waits)}

    def rtf(self) -> tuple[float, float]:
        """Over the whole window, and the lowest over any 1 s of it."""
        wall, sim = (np.array(c) for c in zip(*self.clock, strict=True))
        whole = (sim[-1] - sim[0]) / (wall[-1] - wall[0])
        ends = np.searchsorted(wall, wall + 1.0)
        ok = ends < len(wall)
        lows = (sim[ends[ok]] - sim[ok]) / (wall[ends[ok]] - wall[ok])
        return float(whole), float(lows.min()) if len(lows) else float(whole)


def window(zenoh: Client, zmq: Client, seconds: float) -> tuple[Prober, Prober]:
    stop = threading.Event()
    probers = (Prober(zenoh, stop), Prober(zmq, stop))
    for prober in probers:
        prober.start()
    time.sleep(seconds)  # a benchmark's wall clock, not a synchronisation
    stop.set()
    for prober in probers:
        prober.join(timeout=PROBE_TIMEOUT_S * 2)
    return probers


def measure(engine: str, front: str, clients: int, seconds: float,
            balls: int) -> dict[str, Any]:
    ctx = mp.get_context("spawn")
    with daemon_client(engine, zmq=True) as (daemon, sim), \
            Client(daemon.instance, daemon.zmq_endpoint, timeout=PROBE_TIMEOUT_S) as over_zmq:
        sim.timeout = PROBE_TIMEOUT_S
        build(sim, balls)
        sim.play(rtf=RTF)
        alone = window(sim, over_zmq, min(seconds, 5.0))[0].rtf()[0]
        endpoint = daemon.endpoint if front == "zenoh" else daemon.zmq_endpoint
        started, counts = ctx.Event(), ctx.Queue()
        workers = [ctx.Process(target=perceive, args=(daemon.instance, endpoint,
                                                      seconds + 3, started, counts))
                   for _ in range(clients)]
        for worker in workers:
            worker.start()
        started.set()
        time.sleep(2.0)  # let every client get going before the window opens
        on_zenoh, on_zmq = window(sim, over_zmq, seconds)
        served = sum(counts.get(timeout=seconds + 120) for _ in workers)
        for worker in workers:
            worker.join(timeout=30)
        sim.pause()
    loaded, lowest = on_zenoh.rtf()
    return {"engine": engine, "load_front": front, "clients": clients, "seconds": seconds,
            "balls": balls, "rtf_alone": alone, "rtf_loaded": loaded, "rtf_lowest_1s": lowest,
            "status_zenoh": on_zenoh.latency(), "status_zmq": on_zmq.latency(),
            "perception_per_s": served / (seconds + 3)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--fronts", default="zenoh,zmq")
    parser.add_argument("--clients", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--balls", type=int, default=300)
    parser.add_argument("--json")
    args = parser.parse_args()
    rows = [measure(e, f, args.clients, args.seconds, args.balls)
            for e in args.engines.split(",") for f in args.fronts.split(",")]
    print(f"# perception load on {machine()}: {args.clients} clients rendering "
          f"{CAMERA['width']}x{CAMERA['height']} and casting {RAYS} rays, {args.seconds:g} s, "
          f"{args.balls} balls playing at RTF {RTF}")
    print("| engine | load over | RTF alone | RTF loaded (lowest 1 s) | status Zenoh p50 / p99 "
          "ms (lost) | status ZeroMQ p50 / p99 ms (lost) | perception req/s |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for row in rows:
        z, q = row["status_zenoh"], row["status_zmq"]
        print(f"| {row['engine']} | {row['load_front']} | {row['rtf_alone']:.3f} | "
              f"{row['rtf_loaded']:.3f} ({row['rtf_lowest_1s']:.2f}) | "
              f"{z['p50_ms']:.1f} / {z['p99_ms']:.1f} ({z['lost']}) | "
              f"{q['p50_ms']:.1f} / {q['p99_ms']:.1f} ({q['lost']}) | "
              f"{row['perception_per_s']:.0f} |")
    write_json(args.json, rows)


if __name__ == "__main__":
    main()
