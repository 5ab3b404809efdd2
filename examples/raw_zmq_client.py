"""A client written with nothing but pyzmq, msgpack and docs/protocol.md ("ZeroMQ").

Spawns a ground plane and 100 spheres above it, steps 500 times, reads their poses, reads
one telemetry sample and deletes what it spawned. Run a daemon with a ZeroMQ endpoint first
(`galton-daemon --zmq ipc:///tmp/galton.sock`), then:
python examples/raw_zmq_client.py [ENDPOINT]
"""

from __future__ import annotations

import struct
import sys

import msgpack
import zmq


class RawClient:
    """A DEALER socket: each request is [tag, envelope], each reply [tag, reply map]."""

    def __init__(self, context: zmq.Context, endpoint: str) -> None:
        self.socket = context.socket(zmq.DEALER)
        self.socket.connect(endpoint)
        self.tag = 0

    def call(self, op: str, args: dict) -> dict:
        self.tag += 1
        tag = self.tag.to_bytes(4, "little")
        envelope = msgpack.packb({"v": 1, "op": op, "args": args}, use_bin_type=True)
        self.socket.send_multipart([tag, envelope])
        while True:
            if not self.socket.poll(30_000):
                raise RuntimeError(f"no reply to {op} within 30 s")
            got_tag, reply = self.socket.recv_multipart()
            if got_tag == tag:  # a late reply to an earlier request would be skipped here
                break
        body = msgpack.unpackb(reply)
        if body["code"] != 0:
            raise RuntimeError(f"{op} failed: {body['code_name']}: {body['message']}")
        return body["result"]


def one_telemetry_sample(context: zmq.Context, endpoint: str) -> dict:
    """Subscribe on the PUB endpoint that capabilities names; return the first sample."""
    socket = context.socket(zmq.SUB)
    socket.connect(endpoint)
    socket.subscribe(b"galton/")
    try:
        while socket.poll(10_000):
            topic, data = socket.recv_multipart()
            if topic.endswith(b"/telemetry"):
                return msgpack.unpackb(data)
        raise RuntimeError("no telemetry within 10 s")
    finally:
        socket.close(linger=0)


def main(endpoint: str = "ipc:///tmp/galton.sock") -> tuple[list[float], dict]:
    context = zmq.Context()
    try:
        client = RawClient(context, endpoint)
        names = [f"raw_{i}" for i in range(100)]
        poses = b"".join(struct.pack("<7d", (i % 10) * 0.3, (i // 10) * 0.3, 2.0, 0, 0, 0, 1)
                         for i in range(100))
        group = {"shape": "sphere", "size": [0.1], "names": names, "poses": poses}
        ground = {"shape": "plane", "size": [5.0, 5.0], "names": ["raw_ground"],
                  "poses": struct.pack("<7d", 0, 0, 0, 0, 0, 0, 1), "static": True}
        client.call("spawn", {"groups": [ground, group]})
        client.call("step", {"count": 500})
        result = client.call("get_states", {"names": names})
        heights = [struct.unpack_from("<7d", result["poses"], 56 * i)[2] for i in range(100)]
        telemetry = client.call("capabilities", {})["zmq"]["telemetry"][0]
        sample = one_telemetry_sample(context, telemetry)
        client.call("delete", {"names": [*names, "raw_ground"]})
    finally:
        context.destroy(linger=0)
    print(f"100 spheres fell from 2.0 m onto the ground: heights "
          f"{min(heights):.3f}..{max(heights):.3f} m; "
          f"telemetry: step {sample['step']}, rss {sample['rss_bytes'] / 2**20:.0f} MiB")
    return heights, sample


if __name__ == "__main__":
    main(*sys.argv[1:])
