"""A client written with nothing but zenoh, msgpack and docs/protocol.md.

In a side world of its own (create_world; the daemon's live world is left as it is), on a
ground plane: spawns 100 spheres, steps 500 times, reads their poses, and deletes the world.
Run a daemon first (`galton-daemon`), then:
python examples/raw_protocol_client.py [ENDPOINT [INSTANCE]]
"""

from __future__ import annotations

import json
import os
import struct
import sys

import msgpack
import zenoh

INSTANCE = "galton"
ORIGIN = struct.pack("<7d", 0, 0, 0, 0, 0, 0, 1)


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
    world = f"raw-example-{os.getpid()}"  # its own: nobody else's world is touched
    with zenoh.open(config) as session:
        call(session, instance, "create_world", {"name": world})
        try:
            ground = {"shape": "plane", "size": [5.0, 5.0], "names": ["ground"],
                      "poses": ORIGIN, "static": True}
            names = [f"raw_{i}" for i in range(100)]
            poses = b"".join(struct.pack("<7d", (i % 10) * 0.3, (i // 10) * 0.3, 2.0,
                                         0, 0, 0, 1) for i in range(100))
            group = {"shape": "sphere", "size": [0.1], "names": names, "poses": poses}
            call(session, instance, "spawn", {"world": world, "groups": [ground, group]})
            call(session, instance, "step", {"world": world, "count": 500})
            result = call(session, instance, "get_states", {"world": world, "names": names})
            heights = [struct.unpack_from("<7d", result["poses"], 56 * i)[2]
                       for i in range(100)]
        finally:
            call(session, instance, "delete_world", {"name": world})
    print(f"100 spheres fell from 2.0 m onto the ground: heights "
          f"{min(heights):.3f}..{max(heights):.3f} m")
    return heights


if __name__ == "__main__":
    main(*sys.argv[1:])
