"""Where a step(1) round trip goes inside the daemon, stage by stage.

Usage: python benchmarks/request_path.py ENGINE [--calls 2000] [--json FILE]

The daemon runs in this process, its methods wrapped with timers; a client in a child
process sends ``step(1)`` to a paused world holding a plane and 20 balls (as
``benchmarks/latency.py`` does) and reports its round trip. Printed per stage, p50 and p90
in µs over the last three quarters of the calls: Zenoh's callback (on Zenoh's thread), the
hand-off to the physics thread (callback entry to ``handle`` entry), ``handle``, the loop
until the step starts, ``World.step`` (of which ``Engine.step``), the step's end until the
reply is sent (verification, reply encoding), and the send (``query.reply`` and drop).
The timers add a few µs per stage; compare stages, not the total, with latency.py.
"""

from __future__ import annotations

import argparse
import importlib
import subprocess
import sys
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np
from common import write_json

from galton.client import Client, plane, spheres
from galton.client.sdk.embedded import free_loopback_port
from galton.daemon.core import loop, stepping
from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.fronts import zenoh as zenoh_front
from galton.daemon.fronts.zenoh import ZenohFront
from galton.daemon.server import Daemon, DaemonOptions
from galton.daemon.world.world import World

BALLS = 20
INSTANCE = "request-path"
Span = tuple[float, float]
SPANS: dict[str, list[Span]] = defaultdict(list)


def timed(owner: Any, name: str, label: str) -> None:
    """Wrap ``owner.name`` so that each call's (start, end) is kept under ``label``."""
    original: Callable[..., Any] = getattr(owner, name)

    def wrapper(*args: Any, **kwargs: Any) -> Any:
        started = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            SPANS[label].append((started, time.perf_counter()))
    setattr(owner, name, wrapper)


def instrument(engine: str) -> None:
    timed(ZenohFront, "_on_query", "callback")
    timed(loop.SimLoop, "handle", "handle")
    timed(stepping.Stepping, "run_steps", "run_steps")
    timed(World, "step", "world_step")
    module, name = ENGINE_CLASSES[engine].split(":")
    timed(getattr(importlib.import_module(module), name), "step", "engine_step")
    make_responder = zenoh_front._responder

    def responder(query: Any) -> Callable[[bytes], None]:
        respond = make_responder(query)

        def timed_respond(data: bytes) -> None:
            started = time.perf_counter()
            respond(data)
            SPANS["respond"].append((started, time.perf_counter()))
        return timed_respond
    zenoh_front._responder = responder


def stages(calls: int) -> dict[str, np.ndarray]:
    """Each stage's durations in µs over the step calls (the last 3/4: warm)."""
    keep = calls * 3 // 4
    last = {label: np.asarray(spans[-keep:]) for label, spans in SPANS.items()}
    steps = last["run_steps"]
    return {name: values * 1e6 for name, values in {
        "Zenoh callback": np.diff(last["callback"]).ravel(),
        "hand-off to the physics thread": last["handle"][:, 0] - last["callback"][:, 0],
        "handle (decode, start the job)": np.diff(last["handle"]).ravel(),
        "loop until the step starts": steps[:, 0] - last["handle"][:, 1],
        "World.step": np.diff(last["world_step"]).ravel(),
        "  of which Engine.step": np.diff(last["engine_step"]).ravel(),
        "step end until the reply is sent": last["respond"][:, 0] - last["world_step"][:, 1],
        "send (query.reply, drop)": np.diff(last["respond"]).ravel(),
    }.items()}


def client(endpoint: str, calls: int) -> None:
    """The child process: a scene, then ``calls`` step(1); prints the round trip's p50."""
    names = [f"b{i}" for i in range(BALLS)]
    with Client(INSTANCE, endpoint) as sim:
        sim.spawn(plane(), spheres(names, np.column_stack(
            [np.arange(BALLS) * 0.2, np.zeros(BALLS), np.full(BALLS, 0.05)]), 0.05))
        samples = []
        for _ in range(calls):
            started = time.perf_counter()
            sim.step(1)
            samples.append(time.perf_counter() - started)
    warm = np.asarray(samples[len(samples) // 4:]) * 1e6
    print(f"{np.median(warm):.1f} {np.percentile(warm, 90):.1f}", flush=True)


def measure(engine: str, calls: int) -> dict[str, Any]:
    instrument(engine)
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    daemon = Daemon(DaemonOptions(engine=engine, instance=INSTANCE, listen=[endpoint]))
    daemon.start()
    try:
        child = subprocess.run([sys.executable, __file__, engine, "--client", endpoint,
                                "--calls", str(calls)], capture_output=True, text=True,
                               check=True)
    finally:
        daemon.close()
    p50, p90 = (float(v) for v in child.stdout.split()[-2:])
    return {"engine": engine, "calls": calls, "round_trip_us": {"p50": p50, "p90": p90},
            "stages_us": {name: {"p50": float(np.median(v)), "p90": float(np.percentile(v, 90))}
                          for name, v in stages(calls).items()}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine", choices=sorted(ENGINE_CLASSES))
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--client", metavar="ENDPOINT", help=argparse.SUPPRESS)
    parser.add_argument("--json")
    args = parser.parse_args()
    if args.client:
        client(args.client, args.calls)
        return
    result = measure(args.engine, args.calls)
    print(f"# step(1) inside a {args.engine} daemon, {args.calls} calls; round trip seen by "
          f"the client p50 {result['round_trip_us']['p50']:.0f} µs")
    print("| stage | p50 µs | p90 µs |\n| --- | --- | --- |")
    for name, value in result["stages_us"].items():
        print(f"| {name} | {value['p50']:.1f} | {value['p90']:.1f} |")
    write_json(args.json, result)


if __name__ == "__main__":
    main()
