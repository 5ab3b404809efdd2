"""Control-call latency over ZeroMQ and over Zenoh, each against its raw floor, in one run.

Usage: python benchmarks/transport.py [--calls 2000] [--only zmq|zenoh] [--back-to-back]
       [--json FILE]

For each engine, once per round in a shuffled order (noise falls on all alike; or each
call many times in a row with --back-to-back, as a tight control loop calls): a raw pyzmq
DEALER round trip to a do-nothing ROUTER in another process over ipc (the ZeroMQ floor), a
raw zenoh get to a do-nothing queryable in another process (the Zenoh floor), and the SDK's
``status()`` and ``step(1)`` over ZeroMQ ipc and over Zenoh, on one daemon with a paused
world of a plane and 20 balls; plus one engine step of the same world in this process.
Targets (issue 27): over ZeroMQ, step(1) p50 ≤ 0.10 ms and ≤ 3 × the raw round trip,
status p50 ≤ 0.08 ms; over Zenoh, status p50 ≤ 1.3 × the raw get, step(1) p50 ≤ raw get +
one engine step.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import msgpack
import zmq
from common import ENGINES, daemon_client, machine, percentiles_ms, write_json
from latency import (
    WARM_UP_ROUNDS,
    interleaved,
    local_engine,
    raw_get,
    scene_groups,
    start_null_queryable,
)

from galton.client import Client
from galton.client.transport.session import open_session
from galton.protocol import encode_request


def start_null_router(folder: str) -> tuple[subprocess.Popen[str], str]:
    endpoint = f"ipc://{folder}/null.sock"
    script = Path(__file__).with_name("null_router.py")
    process = subprocess.Popen([sys.executable, str(script), endpoint], stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, text=True)
    assert process.stdout is not None and process.stdout.readline().strip() == "ready"
    return process, endpoint


def raw_zmq(socket: zmq.Socket[bytes]) -> Callable[[], None]:
    """A DEALER round trip of a status request, tagged as the SDK tags its requests."""
    payload = encode_request("status")
    tag = (1).to_bytes(8, "little")

    def call() -> None:
        socket.send_multipart([tag, payload])
        frames = socket.recv_multipart()
        assert frames[0] == tag and msgpack.unpackb(frames[1])["code"] == 0
    return call


ZMQ_ACTIONS = ("raw_zmq", "status_zmq", "step1_zmq")
ZENOH_ACTIONS = ("raw_get", "status_zenoh", "step1_zenoh", "engine_step")


def in_blocks(actions: dict[str, Callable[[], object]], calls: int) -> dict[str, list[float]]:
    """Each action ``calls`` times in a row (back to back: the processes it wakes are still
    awake, as in a tight control loop), after a warm-up of its own."""
    samples: dict[str, list[float]] = {}
    for name, action in actions.items():
        interleaved({name: action}, WARM_UP_ROUNDS)
        samples |= interleaved({name: action}, calls)
    return samples


def measure(engine: str, null_get: str, null_router: str, calls: int,
            only: str | None = None, back_to_back: bool = False) -> dict:
    null_session = open_session(null_get)
    context = zmq.Context()
    dealer = context.socket(zmq.DEALER)
    dealer.connect(null_router)
    local = local_engine(engine)
    try:
        with daemon_client(engine, zmq=True) as (daemon, sim), \
                Client(connect=daemon.zmq_endpoint) as fast:
            sim.spawn(*scene_groups())
            sim.step(200)
            actions = {
                "raw_zmq": raw_zmq(dealer),
                "status_zmq": fast.status,
                "step1_zmq": lambda: fast.step(1),
                "raw_get": raw_get(null_session, "null/@ctl/status"),
                "status_zenoh": sim.status,
                "step1_zenoh": lambda: sim.step(1),
                "engine_step": lambda: local.step(1),
            }
            if only is not None:  # one transport alone: no other's threads beside it
                kept = ZMQ_ACTIONS if only == "zmq" else ZENOH_ACTIONS
                actions = {name: actions[name] for name in kept}
            if back_to_back:
                samples = in_blocks(actions, calls)
            else:
                interleaved(actions, WARM_UP_ROUNDS)
                samples = interleaved(actions, calls)
    finally:
        local.close()
        context.destroy(linger=0)
        null_session.close()
    result: dict = {name: percentiles_ms(values) for name, values in samples.items()}
    p50 = {name: values["p50"] for name, values in result.items()}
    result["engine"] = engine
    if "raw_zmq" in p50:
        result["zmq_step_ratio"] = p50["step1_zmq"] / p50["raw_zmq"]
    if "raw_get" in p50:
        result.update(zenoh_status_ratio=p50["status_zenoh"] / p50["raw_get"],
                      zenoh_step_budget=p50["raw_get"] + p50["engine_step"])
    return result


def cell(result: dict, name: str, digits: int = 3) -> str:
    if name not in result:
        return "-"
    if not isinstance(result[name], dict):
        return f"{result[name]:.2f}" if digits == 2 else f"{result[name]:.3f}"
    return f"{result[name]['p50']:.3f} / {result[name]['p99']:.3f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--json")
    parser.add_argument("--only", choices=("zmq", "zenoh"),
                        help="measure one transport alone (the other's threads stay idle)")
    parser.add_argument("--back-to-back", action="store_true",
                        help="each call many times in a row rather than shuffled rounds")
    args = parser.parse_args()
    null_get, get_endpoint = start_null_queryable()
    with tempfile.TemporaryDirectory(prefix="galton-bench-") as folder:
        null_router, router_endpoint = start_null_router(folder)
        try:
            results = [measure(engine, get_endpoint, router_endpoint, args.calls, args.only,
                               args.back_to_back) for engine in ENGINES]
        finally:
            null_get.communicate("", timeout=10)
            null_router.communicate("", timeout=10)
    alone = (f", {args.only} alone" if args.only else "") + (
        ", back to back" if args.back_to_back else ", shuffled rounds")
    print(f"# control-call latency by transport on {machine()}, {args.calls} calls each, "
          f"{time.strftime('%Y-%m-%d')}{alone} (ms, p50 / p99)")
    print("| engine | raw pyzmq | ZeroMQ status | ZeroMQ step(1) | step / raw | raw zenoh get | "
          "Zenoh status | status / raw | Zenoh step(1) | raw get + engine step |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {cell(r, 'raw_zmq')} | {cell(r, 'status_zmq')} | "
              f"{cell(r, 'step1_zmq')} | {cell(r, 'zmq_step_ratio', 2)} | "
              f"{cell(r, 'raw_get')} | {cell(r, 'status_zenoh')} | "
              f"{cell(r, 'zenoh_status_ratio', 2)} | {cell(r, 'step1_zenoh')} | "
              f"{cell(r, 'zenoh_step_budget')} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
