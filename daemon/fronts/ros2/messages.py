"""ROS messages as rosbags objects: made with every field defaulted, and CDR both ways;
poses and twists between the daemon's packed float64 rows and geometry_msgs."""

from __future__ import annotations

import struct
from functools import lru_cache
from typing import Any

import numpy as np
from rosbags.interfaces import Nodetype

from galton.daemon.fronts.ros2.interfaces import typestore
from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

CDR_HEADER = b"\x00\x01\x00\x00"  # plain CDR, little endian
_NUMPY = {"bool": np.bool_, "int8": np.int8, "uint8": np.uint8, "byte": np.uint8,
          "char": np.uint8, "int16": np.int16, "uint16": np.uint16, "int32": np.int32,
          "uint32": np.uint32, "int64": np.int64, "uint64": np.uint64,
          "float32": np.float32, "float64": np.float64}


def new(typename: str, **fields: Any) -> Any:
    """A message of ``typename`` with ``fields`` set and every other field zero/empty."""
    store = typestore()
    values = {name: fields[name] if name in fields else _default(desc)
              for name, desc in store.fielddefs[typename][1]}
    unknown = set(fields) - set(values)
    if unknown:
        raise KeyError(f"{typename} has no fields {sorted(unknown)}")
    return store.types[typename](**values)


def _default(desc: Any) -> Any:
    kind, rest = desc
    if kind == Nodetype.BASE:
        return "" if rest[0] == "string" else False if rest[0] == "bool" else 0
    if kind == Nodetype.NAME:
        return new(rest)
    (inner_kind, inner), count = rest
    length = count if kind == Nodetype.ARRAY else 0
    if inner_kind == Nodetype.BASE and inner[0] in _NUMPY:
        return np.zeros(length, dtype=_NUMPY[inner[0]])
    return [_default((inner_kind, inner)) for _ in range(length)]


def encode(message: Any, typename: str) -> bytes:
    """CDR little endian, with its 4-byte encapsulation header."""
    return bytes(typestore().serialize_cdr(message, typename))


# Bytes a request may carry past its message's end: rclpy's serialize_message leaves 8
# there (Kilted), and padding to an 8-byte boundary may add up to 7. More is refused
# (issue 46: 50 MB of them were answered OK).
MAX_TRAILING_BYTES = 16


def decode(payload: bytes, typename: str) -> Any:
    """A message from CDR bytes; bytes that do not parse are INVALID_ARGUMENT, and so are
    more than MAX_TRAILING_BYTES past the message's end (a few are allowed: rclpy leaves 8
    there, which rosbags' own deserialize_cdr refuses as a "size mismatch")."""
    if len(payload) < 4 or payload[:2] not in (b"\x00\x00", b"\x00\x01"):
        raise InvalidArgumentError(
            f"the payload is not CDR: it starts {payload[:4].hex() or 'empty'}, not an "
            "encapsulation header such as 00 01 00 00")
    definition = typestore().get_msgdef(typename)
    read = definition.deserialize_cdr_le if payload[1] else definition.deserialize_cdr_be
    try:
        message, end = read(memoryview(payload)[4:], 0, definition.cls, typestore())
    except Exception as exc:
        raise InvalidArgumentError(
            f"the payload is not a CDR {typename}: {brief(str(exc))}") from exc
    trailing = len(payload) - 4 - end
    if trailing > MAX_TRAILING_BYTES:
        raise InvalidArgumentError(
            f"the payload holds {trailing} bytes past the end of its {typename} (at most "
            f"{MAX_TRAILING_BYTES} are allowed): not one request")
    return message


def time_msg(seconds: float) -> Any:
    """builtin_interfaces/Time of a (non-negative) sim time in seconds."""
    total = max(round(seconds * 1e9), 0)
    return new("builtin_interfaces/msg/Time", sec=total // 1_000_000_000,
               nanosec=total % 1_000_000_000)


def header(seconds: float, frame: str = "world") -> Any:
    return new("std_msgs/msg/Header", stamp=time_msg(seconds), frame_id=frame)


def pose_msg(row: np.ndarray) -> Any:
    """geometry_msgs/Pose of one pose row ``x y z qx qy qz qw``."""
    x, y, z, qx, qy, qz, qw = (float(v) for v in row)
    return new("geometry_msgs/msg/Pose",
               position=new("geometry_msgs/msg/Point", x=x, y=y, z=z),
               orientation=new("geometry_msgs/msg/Quaternion", x=qx, y=qy, z=qz, w=qw))


def pose_row(pose: Any) -> list[float]:
    p, q = pose.position, pose.orientation
    return [p.x, p.y, p.z, q.x, q.y, q.z, q.w]


def vector(x: float, y: float, z: float) -> Any:
    return new("geometry_msgs/msg/Vector3", x=float(x), y=float(y), z=float(z))


def twist_msg(row: np.ndarray) -> Any:
    """geometry_msgs/Twist of one twist row ``vx vy vz wx wy wz`` (world frame)."""
    return new("geometry_msgs/msg/Twist", linear=vector(*row[:3]), angular=vector(*row[3:]))


def twist_row(twist: Any) -> list[float]:
    a, w = twist.linear, twist.angular
    return [a.x, a.y, a.z, w.x, w.y, w.z]


def rows(data: bytes, width: int) -> np.ndarray:
    """The daemon's packed float64 rows as an (n, width) array."""
    return np.frombuffer(data, dtype="<f8").reshape(-1, width)


def packed(values: list[list[float]]) -> bytes:
    return np.asarray(values, dtype="<f8").tobytes()


def tf_cdr(names: list[str], poses: np.ndarray, seconds: float, frame: str = "world") -> bytes:
    """A tf2_msgs/TFMessage of ``frame`` -> each name, written straight to CDR: the same
    bytes as ``encode`` (a test holds them equal) at about 1/100 of its cost, which for a
    thousand bodies at 20 Hz is the difference between a few percent of a core and all
    of it. Each transform ends with its 56 bytes of float64, so every one but the first
    starts 8-aligned: the bytes between its stamp and its pose depend only on its name and
    that alignment, and are kept."""
    total = max(round(seconds * 1e9), 0)
    stamp = struct.pack("<iI", total // 1_000_000_000, total % 1_000_000_000)
    rows_bytes = np.ascontiguousarray(poses, dtype="<f8").tobytes()
    parts = [CDR_HEADER, struct.pack("<I", len(names))]
    for index, name in enumerate(names):
        parts += (stamp, _between(frame, name, 4 if index == 0 else 0),
                  rows_bytes[56 * index:56 * index + 56])
    return b"".join(parts)


@lru_cache(maxsize=65536)
def _between(frame: str, name: str, start: int) -> bytes:
    """A transform's bytes after its stamp and before its pose, for a transform starting
    at ``start`` mod 8 (the stamp is 8 bytes: the parent starts at that alignment too)."""
    out = bytearray(_cdr_string(frame))
    out += b"\x00" * (-(start + len(out)) % 4)
    out += _cdr_string(name)
    out += b"\x00" * (-(start + 8 + len(out)) % 8)
    return bytes(out)


def _cdr_string(text: str) -> bytes:
    raw = text.encode() + b"\x00"
    return struct.pack("<I", len(raw)) + raw
