"""What encoding a reply through its declaration would cost (issue 36): the daemon's path
(``encode_reply`` of the handler's result map) against converting that map into the
operation's declared reply Struct first (``msgspec.convert``, which checks it) and then
encoding the same envelope.

Usage: python benchmarks/replies.py [--repeat 2000]
Prints microseconds per reply for each path (the best of 7 rounds taken in turns) and
their ratio, measured in one run.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import msgspec
import numpy as np

from galton.protocol import Reply, ResultCode, encode_reply, pack_f64
from galton.protocol.operations import OPERATIONS


def _status() -> dict[str, Any]:
    return {"state": "paused", "step": 120, "sim_time": 0.24, "timestep": 0.002,
            "target_rtf": 1.0, "rtf": 0.0, "entity_count": 100, "engine": "mujoco",
            "instance": "default", "world": "main", "faulted": False, "controller": None}


def _states(bodies: int) -> dict[str, Any]:
    return {"names": [f"ball_{i}" for i in range(bodies)],
            "poses": pack_f64(np.zeros((bodies, 7))), "twists": pack_f64(np.zeros((bodies, 6)))}


def _worlds(count: int) -> dict[str, Any]:
    row = {"name": "w", "live": False, "engine": "mujoco", "state": "paused", "step": 1,
           "sim_time": 0.002, "entity_count": 3, "faulted": False}
    return {"worlds": [{**row, "name": f"w{i}"} for i in range(count)]}


CASES: dict[str, tuple[str, dict[str, Any]]] = {
    "status": ("status", _status()),
    "step (count)": ("step", {"steps": 10}),
    "get_states (100 bodies)": ("get_states", _states(100)),
    "step reading 100 bodies": ("step", {"steps": 10, **_states(100)}),
    "list_worlds (8)": ("list_worlds", _worlds(8)),
}


def per_call_us(action: Callable[[], object], repeat: int) -> float:
    start = time.perf_counter()
    for _ in range(repeat):
        action()
    return (time.perf_counter() - start) / repeat * 1e6


def best_of(rounds: int, repeat: int, *actions: Callable[[], object]) -> list[float]:
    """Each action's fastest round, the actions taking turns (a load moves them alike)."""
    times = [[per_call_us(a, repeat) for a in actions] for _ in range(rounds)]
    return [min(column) for column in zip(*times, strict=True)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=2000)
    repeat = parser.parse_args().repeat
    print("| reply | encode µs | convert + encode µs | ratio |")
    print("| --- | --- | --- | --- |")
    for label, (op, result) in CASES.items():
        declared = OPERATIONS[op].reply
        assert declared is not None, op

        def plain(result: dict[str, Any] = result) -> bytes:
            return encode_reply(Reply(ResultCode.OK, result=result, step=1, sim_time=0.1))

        def declared_path(result: dict[str, Any] = result,
                          declared: type[msgspec.Struct] = declared) -> bytes:
            checked = msgspec.to_builtins(msgspec.convert(result, declared),
                                          builtin_types=(bytes,))
            return encode_reply(Reply(ResultCode.OK, result=checked, step=1, sim_time=0.1))

        assert msgspec.msgpack.decode(declared_path()) == msgspec.msgpack.decode(plain()) \
            or label.startswith("step"), label  # a step's unset fields come back as nil
        base, typed = best_of(7, repeat // 7 + 1, plain, declared_path)
        print(f"| {label} | {base:.1f} | {typed:.1f} | {typed / base:.2f} |")


if __name__ == "__main__":
    main()
