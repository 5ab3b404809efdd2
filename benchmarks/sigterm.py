"""How long a daemon takes to exit after SIGTERM, idle and in the middle of a long request.

Usage: python benchmarks/sigterm.py [--engines mujoco,pybullet] [--bodies 60000]
           [--busy-cpu 0.2] [--repeat 3] [--json FILE]

"Mid-request": one spawn of ``--bodies`` static spheres is sent, the script waits until the
daemon's CPU time shows it working on it (its process CPU time grows by ``--busy-cpu``
s; 0.02 lands while the payload is still decoded, before the work begins), then sends
SIGTERM and times the exit. The target: within 2 s (galton.daemon.server.SHUTDOWN_GRACE_S
is the grace the physics thread gets before the process exits without it).
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import threading
import time
from typing import Any

import numpy as np
import psutil
from common import ENGINES, machine, write_json

from galton.client import Client, EmbeddedDaemon, spheres
from galton.protocol import GaltonError


def time_exit(daemon: EmbeddedDaemon) -> tuple[float, int | None]:
    assert daemon.process is not None
    started = time.perf_counter()
    daemon.process.send_signal(signal.SIGTERM)
    code = daemon.process.wait(60)
    return time.perf_counter() - started, code


def idle_exit(engine: str) -> tuple[float, int | None]:
    daemon = EmbeddedDaemon(engine, instance=f"sigterm-{engine}").start()
    try:
        return time_exit(daemon)
    finally:
        daemon.stop()


def busy_exit(engine: str, bodies: int, busy_cpu: float) -> tuple[float, int | None]:
    daemon = EmbeddedDaemon(engine, instance=f"sigterm-{engine}").start()
    assert daemon.process is not None
    process = psutil.Process(daemon.process.pid)
    try:
        with Client(daemon.instance, daemon.endpoint, timeout=600) as client:
            names = [f"s{i}" for i in range(bodies)]
            grid = np.column_stack([np.arange(bodies) % 300 * 0.1,
                                    np.arange(bodies) // 300 * 0.1, np.zeros(bodies)])
            group = spheres(names, grid, 0.04, static=True)
            cpu0 = sum(process.cpu_times()[:2])

            def spawn() -> None:
                with contextlib.suppress(GaltonError):  # the daemon went away, as intended
                    client.spawn(group, timeout=600)
            threading.Thread(target=spawn, daemon=True).start()
            deadline = time.monotonic() + 60
            while sum(process.cpu_times()[:2]) - cpu0 < busy_cpu:
                if time.monotonic() > deadline:
                    raise RuntimeError("the daemon never got busy with the spawn")
                time.sleep(0.01)  # polling the process's CPU clock, not synchronising
            return time_exit(daemon)
    finally:
        daemon.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--bodies", type=int, default=60_000)
    parser.add_argument("--busy-cpu", type=float, default=0.2)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--json")
    args = parser.parse_args()
    rows: list[dict[str, Any]] = []
    for engine in args.engines.split(","):
        idle = [idle_exit(engine) for _ in range(args.repeat)]
        busy = [busy_exit(engine, args.bodies, args.busy_cpu) for _ in range(args.repeat)]
        rows.append({"engine": engine, "idle_s": [t for t, _ in idle],
                     "busy_s": [t for t, _ in busy], "codes": [c for _, c in idle + busy]})
    print(f"# SIGTERM to exit on {machine()}: idle, and during a spawn of {args.bodies} bodies")
    print("| engine | idle: max s | mid-request: each s | exit codes |")
    print("| --- | --- | --- | --- |")
    for row in rows:
        print(f"| {row['engine']} | {max(row['idle_s']):.2f} | "
              f"{', '.join(f'{t:.2f}' for t in row['busy_s'])} | {row['codes']} |")
    write_json(args.json, rows)


if __name__ == "__main__":
    main()
