"""What decoding and validating a request costs: the hand path (msgpack unpack, the
envelope's checks, the argument-name check and the handler's own checks) against msgspec
(issue 36): a whole-payload ``msgspec.msgpack.Decoder`` over typed Structs, and the hybrid
the daemon uses (msgpack unpack and the envelope's limits, then ``msgspec.convert`` of the
args into the operation's declared request).

Usage: python benchmarks/decode.py [--repeat 2000]
Prints microseconds per request for each path and each request, and each msgspec path's
ratio to the hand path, measured in one run (a loaded machine moves all of them alike).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Annotated, Any

import msgspec
import numpy as np

from galton.protocol import BodyGroup, DecodeLimits, decode_request, encode_request, pack_f64
from galton.protocol.model import check_names, decode_poses, integer_in
from galton.protocol.operations import OPERATIONS

LIMITS = DecodeLimits(max_bytes=16 * 1024 * 1024, max_depth=16, max_string=4096)
Name = Annotated[str, msgspec.Meta(min_length=1, max_length=128)]


class StepArgs(msgspec.Struct, forbid_unknown_fields=True):
    count: Annotated[int, msgspec.Meta(ge=1, le=10**9)] = 1
    read: list[Name] | None = None


class StatusArgs(msgspec.Struct, forbid_unknown_fields=True):
    pass


class SetStatesArgs(msgspec.Struct, forbid_unknown_fields=True):
    names: list[Name]
    poses: bytes | None = None
    twists: bytes | None = None


class Group(msgspec.Struct, forbid_unknown_fields=True):
    shape: str
    size: list[float]
    names: list[Name]
    poses: bytes
    static: bool = False
    mass: Annotated[float, msgspec.Meta(gt=0, le=1e9)] | None = None


class SpawnArgs(msgspec.Struct, forbid_unknown_fields=True):
    groups: list[Group]


def _envelope(args_type: type) -> type:
    return msgspec.defstruct("Envelope", [("v", int), ("op", str), ("args", args_type),
                                          ("client", str | None, None)],
                             forbid_unknown_fields=True)


def requests(bodies: int) -> dict[str, tuple[bytes, type, Callable[[dict[str, Any]], Any]]]:
    """Each request's payload, its typed args and the hand checks its handler runs."""
    names = [f"ball_{i}" for i in range(bodies)]
    poses = np.tile([0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], (bodies, 1))
    group = {"shape": "sphere", "size": [0.01], "names": names, "poses": pack_f64(poses),
             "mass": 0.01}
    return {
        "status": (encode_request("status", {}), StatusArgs, lambda a: None),
        "step": (encode_request("step", {"count": 100}), StepArgs,
                 lambda a: integer_in(a.get("count", 1), "step.count", 1, 10**9)),
        f"set_states({bodies})": (
            encode_request("set_states", {"names": names, "poses": pack_f64(poses)}),
            SetStatesArgs,
            lambda a: decode_poses(a["poses"], len(check_names(a["names"], "n")), "p")),
        f"spawn({bodies})": (encode_request("spawn", {"groups": [group]}), SpawnArgs,
                             lambda a: [BodyGroup.from_wire(g) for g in a["groups"]]),
    }


def hand(payload: bytes, check: Callable[[dict[str, Any]], Any]) -> None:
    request = decode_request(payload, None, LIMITS)
    OPERATIONS[request.op].check_arg_names(request.args)
    check(request.args)


def timed(run: Callable[[], None], repeat: int) -> float:
    """Microseconds per call, the best of three batches."""
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(repeat):
            run()
        best = min(best, (time.perf_counter() - start) / repeat)
    return best * 1e6


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeat", type=int, default=2000)
    parser.add_argument("--bodies", type=int, default=100)
    options = parser.parse_args()
    print(f"{'request':<20}{'hand µs':>10}{'msgspec µs':>12}{'ratio':>8}"
          f"{'convert µs':>12}{'ratio':>8}")
    for label, (payload, args_type, check) in requests(options.bodies).items():
        decoder = msgspec.msgpack.Decoder(_envelope(args_type))
        is_spawn = args_type is SpawnArgs

        def whole(decoder: Any = decoder, spawn: bool = is_spawn,
                  payload: bytes = payload) -> None:
            body = decoder.decode(payload)
            if spawn:  # the numeric checks msgspec cannot make (rows, quaternions)
                for group in body.args.groups:
                    decode_poses(group.poses, len(group.names), "p")
            elif hasattr(body.args, "poses") and body.args.poses is not None:
                decode_poses(body.args.poses, len(body.args.names), "p")

        def converted(args_type: type = args_type, spawn: bool = is_spawn,
                      payload: bytes = payload) -> None:
            request = decode_request(payload, None, LIMITS)
            args = msgspec.convert(request.args, args_type)
            if spawn:
                for group in args.groups:
                    decode_poses(group.poses, len(group.names), "p")
            elif hasattr(args, "poses") and args.poses is not None:
                decode_poses(args.poses, len(args.names), "p")

        base = timed(lambda payload=payload, check=check: hand(payload, check), options.repeat)
        fast = timed(whole, options.repeat)
        mixed = timed(converted, options.repeat)
        print(f"{label:<20}{base:>10.1f}{fast:>12.1f}{fast / base:>8.2f}"
              f"{mixed:>12.1f}{mixed / base:>8.2f}")


if __name__ == "__main__":
    main()
