"""Round-trip latency of control calls against a raw Zenoh get, measured in one run.

Usage: python benchmarks/latency.py [--calls 2000] [--json FILE]

For each engine, once per round in a shuffled order (so that noise falls on all alike): a raw
``session.get`` to a do-nothing queryable in another process (the floor), ``Client.status()``,
a raw get of ``status`` (no SDK), ``Client.step(1)`` on a paused world holding a plane and
20 balls, and one engine step of the same world measured in this process.
Targets (issue 6): status p50 ≤ 1.3 × raw get p50, status p99 < 2 ms, step(1)
p50 ≤ raw get p50 + one engine step.
"""

from __future__ import annotations

import argparse
import random
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import zenoh
from common import ENGINES, daemon_client, machine, percentiles_ms, write_json

from galton.client import plane, spheres
from galton.client.sdk.embedded import free_loopback_port
from galton.client.transport.session import open_session
from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup, encode_request

BALLS = 20
WARM_UP_ROUNDS = 100


def start_null_queryable() -> tuple[subprocess.Popen[str], str]:
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    script = Path(__file__).with_name("null_queryable.py")
    process = subprocess.Popen([sys.executable, str(script), endpoint], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None and process.stdout.readline().strip() == "ready"
    return process, endpoint


def raw_get(session: zenoh.Session, key: str) -> Callable[[], None]:
    """A get of ``status`` on ``key`` without the SDK, waiting for the end of replies."""
    payload = encode_request("status")

    def get() -> None:
        replies = list(session.get(key, payload=payload, timeout=5))
        assert replies and replies[0].ok is not None
    return get


def scene_groups() -> list[BodyGroup]:
    names = [f"b{i}" for i in range(BALLS)]
    return [plane(), spheres(names, np.column_stack(
        [np.arange(BALLS) * 0.2, np.zeros(BALLS), np.full(BALLS, 0.05)]), 0.05)]


def local_engine(engine_name: str) -> Engine:
    """The same scene in this process: one step of it is what step(1) cannot avoid."""
    engine = create_engine(engine_name)
    engine.spawn(scene_groups())
    engine.step(200)
    return engine


def interleaved(actions: dict[str, Callable[[], object]], rounds: int) -> dict[str, list[float]]:
    """Each action once per round, in a shuffled order: machine noise, and whatever one call
    leaves cold for the next, fall on all of them alike."""
    samples: dict[str, list[float]] = {name: [] for name in actions}
    order = list(actions)
    rng = random.Random(0)
    for _ in range(rounds):
        rng.shuffle(order)
        for name in order:
            started = time.perf_counter()
            actions[name]()
            samples[name].append(time.perf_counter() - started)
    return samples


def measure(engine: str, null_endpoint: str, calls: int) -> dict:
    null_session = open_session(null_endpoint)
    local = local_engine(engine)
    try:
        with daemon_client(engine) as (_daemon, sim):
            sim.spawn(*scene_groups())
            sim.step(200)
            actions = {
                "raw_get_null": raw_get(null_session, "null/@ctl/status"),
                "status_sdk": sim.status,
                "status_raw_get": raw_get(sim.session, sim.keys.control("status")),
                "step1_sdk": lambda: sim.step(1),
                "engine_step": lambda: local.step(1),
            }
            interleaved(actions, WARM_UP_ROUNDS)
            samples = interleaved(actions, calls)
    finally:
        local.close()
        null_session.close()
    result: dict = {name: percentiles_ms(values) for name, values in samples.items()}
    raw_null = result["raw_get_null"]["p50"]
    result.update(engine=engine, status_ratio_p50=result["status_sdk"]["p50"] / raw_null,
                  step1_budget_p50=raw_null + result["engine_step"]["p50"])
    return result


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
