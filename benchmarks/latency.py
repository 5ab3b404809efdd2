"""Round-trip latency of control calls against a raw Zenoh get, measured in one run.

Usage: python benchmarks/latency.py [--calls 2000] [--json FILE]

For each engine: a raw ``session.get`` to a do-nothing queryable in another process (the
floor), ``Client.status()``, a raw get of ``status`` (no SDK), ``Client.step(1)`` on a
paused world holding a plane and 20 balls, and one engine step of the same world measured
in-process. Targets (issue 6): status p50 ≤ 1.3 × raw get p50, status p99 < 2 ms, step(1)
p50 ≤ raw get p50 + one engine step.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from common import ENGINES, daemon_client, machine, percentiles_ms, timed, write_json

from galton.client import Client, plane, spheres
from galton.client.embedded import free_loopback_port
from galton.client.session import open_session
from galton.daemon.engines import create_engine
from galton.protocol import encode_request

BALLS = 20


def start_null_queryable() -> tuple[subprocess.Popen[str], str]:
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    script = Path(__file__).with_name("null_queryable.py")
    process = subprocess.Popen([sys.executable, str(script), endpoint], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None and process.stdout.readline().strip() == "ready"
    return process, endpoint


def raw_get_samples(endpoint: str, key: str, calls: int) -> list[float]:
    session = open_session(endpoint)
    payload = encode_request("status")

    def get() -> None:
        replies = list(session.get(key, payload=payload, timeout=5))
        assert replies and replies[0].ok is not None

    try:
        timed(get, 100)
        return timed(get, calls)
    finally:
        session.close()


def scene(sim: Client) -> None:
    names = [f"b{i}" for i in range(BALLS)]
    sim.spawn(plane(), spheres(names, np.column_stack(
        [np.arange(BALLS) * 0.2, np.zeros(BALLS), np.full(BALLS, 0.05)]), 0.05))
    sim.step(200)


def engine_step_samples(engine_name: str, calls: int) -> list[float]:
    """One engine step of the same scene, in this process: what step(1) cannot avoid."""
    from galton.client import plane as plane_group

    engine = create_engine(engine_name)
    groups = [plane_group(), spheres([f"b{i}" for i in range(BALLS)], np.column_stack(
        [np.arange(BALLS) * 0.2, np.zeros(BALLS), np.full(BALLS, 0.05)]), 0.05)]
    engine.spawn(groups)
    engine.step(200)
    samples = timed(lambda: engine.step(1), calls)
    engine.close()
    return samples


def measure(engine: str, null_endpoint: str, calls: int) -> dict:
    raw_null = percentiles_ms(raw_get_samples(null_endpoint, "null/@ctl/status", calls))
    with daemon_client(engine) as (daemon, sim):
        scene(sim)
        timed(sim.status, 100)
        status = percentiles_ms(timed(sim.status, calls))
        raw_status = percentiles_ms(raw_get_samples(daemon.endpoint,
                                                    sim.keys.control("status"), calls))
        step = percentiles_ms(timed(lambda: sim.step(1), calls))
    engine_step = percentiles_ms(engine_step_samples(engine, calls))
    return {"engine": engine, "raw_get_null": raw_null, "status_sdk": status,
            "status_raw_get": raw_status, "step1_sdk": step, "engine_step": engine_step,
            "status_ratio_p50": status["p50"] / raw_null["p50"],
            "step1_budget_p50": raw_null["p50"] + engine_step["p50"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--json")
    args = parser.parse_args()
    null, endpoint = start_null_queryable()
    try:
        results = [measure(engine, endpoint, args.calls) for engine in ENGINES]
    finally:
        null.communicate("", timeout=10)
    print(f"# control-call latency on {machine()}, {args.calls} calls each, "
          f"{time.strftime('%Y-%m-%d')}")
    print("| engine | raw get (null) p50 / p99 | status p50 / p99 | status / raw p50 | raw get "
          "of status p50 | step(1) p50 / p99 | raw get + engine step p50 |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['raw_get_null']['p50']:.3f} / {r['raw_get_null']['p99']:.3f}"
              f" ms | {r['status_sdk']['p50']:.3f} / {r['status_sdk']['p99']:.3f} ms | "
              f"{r['status_ratio_p50']:.2f} | {r['status_raw_get']['p50']:.3f} ms | "
              f"{r['step1_sdk']['p50']:.3f} / {r['step1_sdk']['p99']:.3f} ms | "
              f"{r['step1_budget_p50']:.3f} ms |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
