"""A client written with nothing but zenoh, msgpack and docs/protocol.md.

Spawns 100 spheres, steps 500 times, reads their poses and deletes them.
Run a daemon first (`galton-daemon`), then: python examples/raw_protocol_client.py [ENDPOINT]
"""

from __future__ import annotations

import json
import struct
import sys

import msgpack
import zenoh

INSTANCE = "galton"


def call(session: zenoh.Session, instance: str, op: str, args: dict) -> dict:
    """One request: msgpack {v, op, args} to galton/<instance>/@ctl/<op>."""
    payload = msgpack.packb({"v": 1, "op": op, "args": args}, use_bin_type=True)
    for reply in session.get(f"galton/{instance}/@ctl/{op}", payload=payload, timeout=30):
        body = msgpack.unpackb(reply.ok.payload.to_bytes())
        if body["code"] != 0:
            raise RuntimeError(f"{op} failed: {body['code_name']}: {body['message']}")
        return body["result"]
    raise RuntimeError(f"no daemon answered {op}")


def main(endpoint: str = "tcp/127.0.0.1:7460", instance: str = INSTANCE) -> list[float]:
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([endpoint]))
    with zenoh.open(config) as session:
        names = [f"raw_{i}" for i in range(100)]
        poses = b"".join(struct.pack("<7d", (i % 10) * 0.3, (i // 10) * 0.3, 2.0, 0, 0, 0, 1)
                         for i in range(100))
        group = {"shape": "sphere", "size": [0.1], "names": names, "poses": poses}
        call(session, instance, "spawn", {"groups": [group]})
        call(session, instance, "step", {"count": 500})
        result = call(session, instance, "get_states", {"names": names})
        heights = [struct.unpack_from("<7d", result["poses"], 56 * i)[2] for i in range(100)]
        call(session, instance, "delete", {"names": names})
    print(f"100 spheres fell from 2.0 m to {min(heights):.3f}..{max(heights):.3f} m")
    return heights


if __name__ == "__main__":
    main(*sys.argv[1:])
