"""On demand (``-m ros2_tools``): the front's CDR against ROS 2's own rclpy, both ways,
for every standard message type it sends or takes. Needs Kilted's wheels in the venv:

    pip install ros-rclpy ros-rmw-fastrtps-cpp ros-std-msgs ros-rosgraph-msgs \\
        ros-geometry-msgs ros-sensor-msgs

(~280 MB and ~80 s to install, so not in [test]; tests/daemon/fronts/test_ros2_wire.py holds
fixed bytes rclpy made once.) Byte equality is checked on every byte that is the message's: Fast-CDR
leaves alignment padding uninitialised, so those bytes are compared by decoding instead."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from galton.daemon.fronts.ros2 import interfaces
from galton.daemon.fronts.ros2.messages import decode, encode, header, new, pose_msg, twist_msg

pytestmark = [pytest.mark.ros2_tools,
              # rosidl's parser imports lark, which imports the deprecated sre_* modules
              pytest.mark.filterwarnings("ignore:module 'sre_.*' is deprecated")]
SEED = 40


def ours(rng: np.random.Generator) -> dict[str, Any]:
    """One message of each standard type the front uses, with random values."""
    pose = np.concatenate([rng.normal(size=3), rng.normal(size=4)])
    return {
        interfaces.CLOCK: new(interfaces.CLOCK, clock=new(
            "builtin_interfaces/msg/Time", sec=int(rng.integers(0, 2**31)),
            nanosec=int(rng.integers(0, 10**9)))),
        interfaces.JOINT_STATE: new(
            interfaces.JOINT_STATE, header=header(float(rng.uniform(0, 100)), "base"),
            name=[f"joint_{i}" for i in range(7)], position=rng.normal(size=7),
            velocity=rng.normal(size=7), effort=np.zeros(0)),
        "geometry_msgs/msg/Pose": pose_msg(pose),
        "geometry_msgs/msg/Twist": twist_msg(rng.normal(size=6)),
        "std_msgs/msg/Header": header(float(rng.uniform(0, 100)), "world"),
    }


def rclpy_class(typename: str) -> Any:
    package, _, name = typename.split("/")
    module = __import__(f"{package}.msg", fromlist=[name])
    return getattr(module, name)


def test_rclpy_reads_our_bytes_and_we_read_its() -> None:
    from rclpy.serialization import deserialize_message, serialize_message

    rng = np.random.default_rng(SEED)
    for _ in range(20):
        for typename, message in ours(rng).items():
            data = encode(message, typename)
            theirs = deserialize_message(data, rclpy_class(typename))
            again = serialize_message(theirs)
            assert encode(decode(again, typename), typename) == data, typename
            assert deserialize_message(again, rclpy_class(typename)) == theirs
