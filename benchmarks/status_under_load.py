"""Status latency while the physics thread is busy: a second client polls ``status`` every
2 ms while the first runs a 300-ball all-at-once trial's first 4 s of sim time.

Usage: python benchmarks/status_under_load.py [--engines mujoco,pybullet] [--params JSON]
           [--json FILE]

``--params`` sets daemon parameters first, e.g. '{"mujoco.threads": 0}' to compare MuJoCo
with its worker threads off.

Status is answered on Zenoh's thread from a snapshot, so it should not wait for physics;
an engine that holds the GIL while stepping (PyBullet) needs the loop's short switch
interval for that (see galton.daemon.core.loop).
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from typing import Any

from bridge_overhead import trial_config
from common import ENGINES, daemon_client, machine, percentiles_ms, write_json

from galton.client import Client
from galton.client.bench.build import ball_group
from galton.client.bench.trial import prepare_world

BALLS = 300
POLL_S = 0.002


def measure(engine: str, params: dict[str, Any]) -> dict:
    config = trial_config(engine, BALLS, params)
    with daemon_client(engine) as (daemon, sim), Client(daemon.instance,
                                                        daemon.endpoint) as probe:
        shake, names = prepare_world(sim, config)
        sim.spawn(ball_group(config.board, engine, names, shake.release.positions))
        samples: list[float] = []
        done = threading.Event()

        def poll() -> None:
            while not done.wait(POLL_S):
                started = time.perf_counter()
                probe.status()
                samples.append(time.perf_counter() - started)

        poller = threading.Thread(target=poll)
        poller.start()
        sim.run_until(4.0)
        done.set()
        poller.join()
    return {"engine": engine, **percentiles_ms(samples)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--params", default="{}", help="daemon parameters as JSON")
    parser.add_argument("--json")
    args = parser.parse_args()
    params = json.loads(args.params)
    results = [measure(engine, params) for engine in args.engines.split(",")]
    print(f"# status under load on {machine()}: {BALLS} balls falling, polled every 2 ms")
    print("| engine | calls | p50 (ms) | p99 (ms) |")
    print("| --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['n']} | {r['p50']:.2f} | {r['p99']:.2f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
