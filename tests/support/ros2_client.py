"""A ROS 2 service client written from rmw_zenoh's docs/design.md alone, sharing no code
with the daemon's front: its own key expressions, attachments, liveliness parsing and a
hand-written CDR reader and writer. The type hashes are the values rosidl computed from
simulation_interfaces 2.1 (tests/support/ros2_rosidl_hashes.json, made by
tests/support/ros2_rosidl.py)."""

from __future__ import annotations

import json
import os
import struct
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import zenoh

HASHES: dict[str, str] = json.loads(
    (Path(__file__).parent / "ros2_rosidl_hashes.json").read_text())


class Cdr:
    """Plain CDR, little endian, aligned from the end of the 4-byte encapsulation."""

    def __init__(self, data: bytes = b"") -> None:
        self.data, self.at = bytearray(data), 4

    # writing
    @classmethod
    def writer(cls) -> Cdr:
        return cls(b"\x00\x01\x00\x00")

    def _pad(self, size: int) -> None:
        self.data += b"\x00" * (-(len(self.data) - 4) % size)

    def put(self, fmt: str, *values: Any) -> Cdr:
        self._pad(struct.calcsize(fmt.lstrip("0123456789")[0]))
        self.data += struct.pack("<" + fmt, *values)
        return self

    def put_string(self, text: str) -> Cdr:
        raw = text.encode() + b"\x00"
        self.put("I", len(raw)).data += raw
        return self

    # reading
    def get(self, fmt: str) -> Any:
        size = struct.calcsize(fmt.lstrip("0123456789")[0])
        self.at += -(self.at - 4) % size
        values = struct.unpack_from("<" + fmt, self.data, self.at)
        self.at += struct.calcsize("<" + fmt)
        return values[0] if len(values) == 1 else values

    def get_string(self) -> str:
        length = self.get("I")
        raw = bytes(self.data[self.at:self.at + length])
        self.at += length
        return raw.rstrip(b"\x00").decode()

    def get_result(self) -> tuple[int, str]:
        return self.get("B"), self.get_string()


def put_pose_stamped(cdr: Cdr, frame: str, xyz: tuple[float, float, float],
                     quaternion: tuple[float, ...] = (0.0, 0.0, 0.0, 1.0)) -> None:
    cdr.put("iI", 0, 0).put_string(frame)
    cdr.put("3d", *xyz).put("4d", *quaternion)


@dataclass
class Token:
    """A liveliness token's fields, by the design document's layout."""

    domain: str
    zid: str
    kind: str
    namespace: str
    node: str
    name: str = ""
    type_name: str = ""
    type_hash: str = ""


def parse_token(key: str) -> Token:
    parts = key.split("/")
    assert parts[0] == "@ros2_lv"
    demangle = lambda text: text.replace("%", "/")  # noqa: E731
    token = Token(parts[1], parts[2], parts[5], demangle(parts[7]), parts[8])
    if len(parts) > 9:
        token.name, token.type_name, token.type_hash = demangle(parts[9]), parts[10], parts[11]
    return token


class RosClient:
    """Calls services like rcl on rmw_zenoh would, from one Zenoh session."""

    def __init__(self, endpoint: str, domain: int = 0) -> None:
        config = zenoh.Config()
        config.insert_json5("mode", '"client"')
        config.insert_json5("connect/endpoints", json.dumps([endpoint]))
        self.session = zenoh.open(config)
        self.domain = domain
        self.gid = os.urandom(16)
        self.sequence = 0

    def graph(self) -> list[Token]:
        """Every entity of the domain, read from its liveliness token (`ros2 node list`)."""
        replies = self.session.liveliness().get(f"@ros2_lv/{self.domain}/**", timeout=5)
        return [parse_token(str(reply.ok.key_expr)) for reply in replies if reply.ok]

    def key(self, name: str, service: str) -> str:
        """The key of a simulation_interfaces service, or of any ``pkg/kind/Name`` type."""
        ros_type = service if "/" in service else f"simulation_interfaces/srv/{service}"
        package, kind, type_name = ros_type.split("/")
        return (f"{self.domain}/{name.lstrip('/')}/{package}::{kind}::dds_::{type_name}_/"
                f"{HASHES[ros_type]}")

    def call(self, name: str, service: str, request: bytes,
             timeout: float = 10.0) -> tuple[Cdr, bytes]:
        """One request; the response as a reader, and the reply's attachment."""
        self.sequence += 1
        attachment = struct.pack("<qqB", self.sequence, time.time_ns(), 16) + self.gid
        replies = list(self.session.get(self.key(name, service), payload=request,
                                        attachment=attachment, timeout=timeout,
                                        target=zenoh.QueryTarget.ALL_COMPLETE))
        assert len(replies) == 1, f"{service}: {len(replies)} replies"
        reply = replies[0]
        if reply.ok is None:
            raise RuntimeError(reply.err.payload.to_string())
        sample = reply.ok
        return Cdr(sample.payload.to_bytes()), sample.attachment.to_bytes()

    def close(self) -> None:
        self.session.close()


def topic_key(domain: int, topic: str, dds_type: str, ros_type: str) -> str:
    return f"{domain}/{topic.lstrip('/')}/{dds_type}/{HASHES[ros_type]}"


CLOCK_KEY = ("rosgraph_msgs::msg::dds_::Clock_", "rosgraph_msgs/msg/Clock")
TF_KEY = ("tf2_msgs::msg::dds_::TFMessage_", "tf2_msgs/msg/TFMessage")
JOINT_STATE_KEY = ("sensor_msgs::msg::dds_::JointState_", "sensor_msgs/msg/JointState")


def read_clock(payload: bytes) -> float:
    sec, nanosec = Cdr(payload).get("iI")
    return float(sec + nanosec * 1e-9)


def read_tf(payload: bytes) -> dict[str, tuple[float, ...]]:
    """child frame -> (x, y, z, qx, qy, qz, qw) of a TFMessage."""
    cdr, frames = Cdr(payload), {}
    for _ in range(cdr.get("I")):
        cdr.get("iI")
        assert cdr.get_string() == "world"
        child = cdr.get_string()
        frames[child] = (*cdr.get("3d"), *cdr.get("4d"))
    return frames


def joint_state(names: list[str], positions: list[float]) -> bytes:
    cdr = Cdr.writer().put("iI", 0, 0).put_string("").put("I", len(names))
    for name in names:
        cdr.put_string(name)
    cdr.put("I", len(positions))
    for value in positions:
        cdr.put("d", value)
    return bytes(cdr.put("I", 0).put("I", 0).data)
