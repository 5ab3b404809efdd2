"""Idle CPU of a daemon with ``--ros2`` against a plain one (issue 47, item 3).

Usage: python benchmarks/ros2_idle.py [--seconds 20] [--engine mujoco] [--json FILE]

Each daemon is started fresh with the same engine and telemetry rate, left paused and
untouched (no client request during the window), and its process CPU time (user + system,
from the OS) is read over ``--seconds``; the two run one after the other, never together.
Target: the ``--ros2`` daemon costs at most 2 x the plain one + 0.5 points of a core.
Run it on a quiet machine: on a loaded one, each process's CPU time grows with the load.
"""

from __future__ import annotations

import argparse
import time

import psutil
from common import machine, write_json

from galton.client import Client, EmbeddedDaemon, wait_for_daemon

SETTLE_S = 3.0  # after the ready line: imports, the first telemetry, the ROS 2 graph


def idle_percent(engine: str, extra: list[str], seconds: float) -> float:
    """% of one core the daemon's process uses over ``seconds`` while idle."""
    with EmbeddedDaemon(engine, instance=f"idle-{engine}", extra_args=extra) as daemon:
        with Client(daemon.instance, daemon.endpoint) as client:
            wait_for_daemon(client.session, daemon.instance, 30)
        assert daemon.process is not None
        process = psutil.Process(daemon.process.pid)
        time.sleep(SETTLE_S)
        before, started = sum(process.cpu_times()[:2]), time.monotonic()
        time.sleep(seconds)
        used = sum(process.cpu_times()[:2]) - before
        return 100 * used / (time.monotonic() - started)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--json")
    args = parser.parse_args()
    plain = idle_percent(args.engine, [], args.seconds)
    ros2 = idle_percent(args.engine, ["--ros2"], args.seconds)
    bound = 2 * plain + 0.5
    print(f"# idle daemon CPU ({args.engine}, {args.seconds:g} s each) on {machine()}")
    print("| daemon | idle CPU (% of a core) |")
    print("| --- | --- |")
    print(f"| plain | {plain:.2f} |")
    print(f"| --ros2 | {ros2:.2f} |")
    verdict = "met" if ros2 <= bound else "MISSED"
    print(f"target: --ros2 <= 2 x plain + 0.5 = {bound:.2f}: {verdict}")
    write_json(args.json, {"engine": args.engine, "seconds": args.seconds,
                           "plain_percent": plain, "ros2_percent": ros2, "bound": bound})


if __name__ == "__main__":
    main()
