"""Mirror a robot: stream a recorded joint trajectory into the daemon at 100 Hz and read the
end effector back, as a robot's internal model follows the real arm.

Loads pybullet_data's KUKA iiwa (fixed base) and generates a seeded "recording": smooth
sums of sinusoids inside the joint limits, one sample per 10 ms. Each cycle sends the
sample (positions and velocities) and reads the flange link's pose where those joints put
it, in the same reply (set_joint_states with read: one round trip per cycle). The program
prints the p50 and p99 of that round trip.

Starts its own daemon on a free loopback port unless --connect is given:
python examples/mirror_robot.py [--engine mujoco|pybullet] [--seconds S] [--seed N]
                                [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet_data

from galton.client import Client, EmbeddedDaemon, JointInfo

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
END_EFFECTOR = "lbr_iiwa_link_7"
RATE_HZ = 100.0
HARMONICS = 3  # sinusoids per joint in the recording


@dataclass(frozen=True)
class MirrorRun:
    """What one run measured: cycles, round trips (ms) and where the flange went (m)."""

    cycles: int
    p50_ms: float  # the cycle's one round trip: set the joints, read the flange
    p99_ms: float
    flange: np.ndarray  # (cycles, 3) positions read back, world frame


def recording(joints: list[JointInfo], cycles: int, seed: int) -> tuple[np.ndarray,
                                                                       np.ndarray]:
    """Positions and velocities (cycles, joints): per joint a seeded sum of slow sinusoids
    kept within 80 % of its limits (±1 rad for an unlimited one)."""
    rng = np.random.default_rng(seed)
    t = np.arange(cycles)[:, None] / RATE_HZ
    lower = np.array([-1.0 if j.lower is None else j.lower for j in joints])
    upper = np.array([1.0 if j.upper is None else j.upper for j in joints])
    middle, half = (upper + lower) / 2, 0.8 * (upper - lower) / 2
    positions, velocities = np.zeros((cycles, len(joints))), np.zeros((cycles, len(joints)))
    for _ in range(HARMONICS):
        amplitude = half / HARMONICS * rng.uniform(0.3, 1.0, len(joints))
        omega = 2 * np.pi * rng.uniform(0.1, 0.8, len(joints))
        phase = rng.uniform(0, 2 * np.pi, len(joints))
        positions += amplitude * np.sin(omega * t + phase)
        velocities += amplitude * omega * np.cos(omega * t + phase)
    return middle + positions, velocities


def mirror(sim: Client, seconds: float, seed: int) -> MirrorRun:
    """Stream ``seconds`` of the recording at 100 Hz (paced by the wall clock)."""
    sim.reset("all")
    sim.load_model("urdf", text=KUKA.read_text(), search_path=[KUKA.parent], fixed_base=True)
    joints = [j for j in sim.joints() if j.type == "revolute"]
    names = [j.name for j in joints]
    cycles = max(1, round(seconds * RATE_HZ))
    positions, velocities = recording(joints, cycles, seed)
    round_trips, flange = np.zeros(cycles), np.zeros((cycles, 3))
    start = time.perf_counter()
    for i in range(cycles):
        time.sleep(max(0.0, start + i / RATE_HZ - time.perf_counter()))  # the 100 Hz pace
        sent = time.perf_counter()
        states = sim.set_joint_states_and_read(names, positions[i], [END_EFFECTOR],
                                               velocities[i])
        round_trips[i] = time.perf_counter() - sent
        flange[i] = states.positions[0]
    p50, p99 = np.percentile(round_trips, [50, 99]) * 1e3
    print(f"{sim.status().engine}: {cycles} cycles at {RATE_HZ:g} Hz; round trip (set "
          f"joints, read the flange) p50 {p50:.2f} ms, p99 {p99:.2f} ms; flange travelled "
          f"{np.sum(np.linalg.norm(np.diff(flange, axis=0), axis=1)):.3f} m")
    return MirrorRun(cycles, float(p50), float(p99), flange)


def main(argv: list[str]) -> MirrorRun:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--seconds", type=float, default=5.0, help="length of the recording")
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=30.0) as sim:
            return mirror(sim, args.seconds, args.seed)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as sim:
        return mirror(sim, args.seconds, args.seed)


if __name__ == "__main__":
    main(sys.argv[1:])
