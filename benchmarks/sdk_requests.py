"""What building a request on its declared type costs the SDK, per request, in this process.

Usage: python benchmarks/sdk_requests.py [--calls 20000] [--json FILE]

Since issue 50 each SDK method builds its operation's declared request (a msgspec Struct)
and ``Client._send`` encodes it and checks the map with the daemon's ``decode_args``
before it is sent (client/sdk/sending.py). For a few requests of a control loop, printed
in µs (p50, p90 over the calls): the hand-made map the SDK built before (``dict``), the
Struct built and encoded (``struct``), and that map checked too (``checked``, what
``_send`` adds to a round trip). No daemon runs: compare ``checked - dict`` with a round
trip of ``benchmarks/latency.py``.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np
from common import write_json

from galton.client.sdk import joints as sdk_joints
from galton.client.sdk.sending import wire_args
from galton.protocol import pack_f64
from galton.protocol import requests as rq

NAMES = [f"ball_{i}" for i in range(20)]
JOINTS = [f"joint_{i}" for i in range(7)]
POSES = np.tile([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], (20, 1))
TARGETS = np.linspace(-0.5, 0.5, 7)


def cases() -> dict[str, tuple[str, Callable[[], Any], Callable[[], rq.Args]]]:
    """name: (op, the map as the SDK built it before issue 50, the declared request)."""
    return {
        "step(1)": ("step", lambda: {"count": 1}, lambda: rq.Step(count=1)),
        "step_and_read(1, 20 names)": (
            "step", lambda: {"count": 1, "read": list(NAMES)},
            lambda: sdk_joints.step_request(1, NAMES, None)),
        "set_joint_targets(7 joints)": (
            "set_joint_targets",
            lambda: {"names": list(JOINTS), "mode": "position",
                     "targets": pack_f64(TARGETS), "kp": pack_f64(np.full(7, 50.0))},
            lambda: sdk_joints.set_joint_targets_request(JOINTS, "position", TARGETS,
                                                         kp=50.0)),
        "set_states(20 bodies)": (
            "set_states", lambda: {"names": list(NAMES), "poses": pack_f64(POSES)},
            lambda: sdk_joints.set_states_request(NAMES, POSES)),
    }


def timed(make: Callable[[], Any], calls: int) -> dict[str, float]:
    spent = np.empty(calls)
    for i in range(calls):
        started = time.perf_counter()
        make()
        spent[i] = time.perf_counter() - started
    return {"p50": float(np.percentile(spent, 50) * 1e6),
            "p90": float(np.percentile(spent, 90) * 1e6)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20_000)
    parser.add_argument("--json")
    args = parser.parse_args()
    found: dict[str, dict[str, dict[str, float]]] = {}
    for name, (op, hand_made, declared) in cases().items():
        wire_args(op, declared())  # warm up, and the request is a good one
        found[name] = {
            "dict": timed(hand_made, args.calls),
            "struct": timed(lambda declared=declared: rq.encode_args(declared()), args.calls),
            "checked": timed(lambda op=op, declared=declared: wire_args(op, declared()),
                             args.calls)}
        print(f"{name:30s}" + "".join(
            f"  {kind} {t['p50']:6.2f} / {t['p90']:6.2f} µs" for kind, t in found[name].items()))
    write_json(args.json, found)


if __name__ == "__main__":
    main()
