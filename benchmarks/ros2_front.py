"""The ROS 2 front's targets (issue 40), measured in one run on one MuJoCo daemon.

Usage: python benchmarks/ros2_front.py [--calls 1000] [--seconds 3] [--json FILE]

- StepSimulation(1) round trip over the ROS 2 front (a client written from rmw_zenoh's
  design document, tests/support/ros2_client.py) against the native ``Client.step(1)`` over Zenoh,
  interleaved call by call on the same paused world. Target: p50 ratio <= 1.5.
- /clock while playing at RTF 1: messages per second and the measured RTF. Target: >= 100
  Hz, RTF unmoved.
- Mirroring a 7-joint arm (KUKA iiwa) from JointState messages at 100 Hz: before each
  message, how many messages the arm's joints are behind the last one sent. Target: <= 1.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pybullet_data
from common import machine, percentiles_ms, write_json

sys.path.insert(0, str(Path(__file__).parents[1] / "tests"))
from support.ros2_client import (
    CLOCK_KEY,
    JOINT_STATE_KEY,
    Cdr,
    RosClient,
    joint_state,
    topic_key,
)

from galton.client import Client, EmbeddedDaemon, spheres, wait_for_daemon

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]
MIRROR_HZ = 100.0


def step_round_trips(ros: RosClient, native: Client, calls: int) -> dict[str, object]:
    request = bytes(Cdr.writer().put("Q", 1).data)
    ros_times, native_times = [], []
    for _ in range(calls):
        started = time.perf_counter()
        reply, _ = ros.call("/bench/step_simulation", "StepSimulation", request)
        ros_times.append(time.perf_counter() - started)
        assert reply.get("B") == 1
        started = time.perf_counter()
        native.step(1)
        native_times.append(time.perf_counter() - started)
    ros_p, native_p = percentiles_ms(ros_times), percentiles_ms(native_times)
    return {"ros2_step_ms": ros_p, "native_step_ms": native_p,
            "p50_ratio": ros_p["p50"] / native_p["p50"]}


def clock_rate(ros: RosClient, native: Client, seconds: float) -> dict[str, float]:
    stamps: list[float] = []
    subscriber = ros.session.declare_subscriber(topic_key(0, "/clock", *CLOCK_KEY),
                                                lambda sample: stamps.append(time.time()))
    native.play(1.0)
    time.sleep(seconds)  # a measurement window, not synchronisation
    rtf = native.status().rtf
    native.pause()
    subscriber.undeclare()
    return {"clock_hz": len(stamps) / seconds, "rtf_while_publishing": rtf}


def mirror_lag(ros: RosClient, native: Client, seconds: float) -> dict[str, float]:
    native.call("load_model", {"format": "urdf", "text": KUKA.read_text(),
                               "search_path": str(KUKA.parent), "prefix": "arm/"})
    names = [f"arm/{joint}" for joint in JOINTS]
    publisher = ros.session.declare_publisher(topic_key(0, "/joint_states", *JOINT_STATE_KEY))
    attachment = (1).to_bytes(8, "little") * 2 + b"\x10" + ros.gid
    lags = []
    count = int(seconds * MIRROR_HZ)
    start = time.perf_counter()
    for index in range(1, count + 1):
        time.sleep(max(0.0, start + index / MIRROR_HZ - time.perf_counter()))  # pacing
        if index > 1:
            shown = native.get_joint_states(names).positions[0] * 1000.0
            lags.append(index - 1 - round(shown))
        publisher.put(joint_state(JOINTS, [index / 1000.0] * 7), attachment=attachment)
    publisher.undeclare()
    data = np.asarray(lags)
    return {"messages": count, "lag_max": float(data.max()),
            "lag_p99": float(np.percentile(data, 99)), "lag_mean": float(data.mean())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=1000)
    parser.add_argument("--seconds", type=float, default=3.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    with EmbeddedDaemon("mujoco", instance="bench", extra_args=[
            "--ros2", "--ros2-mirror", "arm=/joint_states"]) as daemon, \
            Client(daemon.instance, daemon.endpoint) as native:
        wait_for_daemon(native.session, daemon.instance, 30)
        ros = RosClient(daemon.endpoint)
        native.spawn(spheres(["ball"], np.array([[0.0, 0.0, 1.0]]), 0.05))
        native.step(1)  # paused
        results = {"machine": machine(), **step_round_trips(ros, native, args.calls),
                   **clock_rate(ros, native, args.seconds),
                   **mirror_lag(ros, native, args.seconds)}
        ros.close()
    for key, value in results.items():
        print(f"{key}: {value}")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
