"""A PD-controlled arm: pybullet_data's KUKA iiwa reaches a joint-space target and holds it.

The daemon's engine applies tau = kp (target - q) - kd q' on every joint, every step,
clipped to max_effort (set_joint_targets, mode "position"): no Python runs per step. The
arm starts upright, in its as-loaded pose; after SECONDS of sim time the program prints
each joint's remaining error: what is left is gravity's torque over kp (a PD law has no
integral term). Gains fall along the chain with the inertia each joint moves. The law is
explicit (computed from the state before each step), so the light wrist needs a short
step: the program sets 1 ms (PyBullet's default 1/240 s lets the wrist oscillate at these
gains).

Starts its own daemon on a free loopback port unless --connect is given:
python examples/pd_arm.py [--engine mujoco|pybullet] [--seconds S]
                          [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pybullet_data

from galton.client import Client, EmbeddedDaemon, JointStates

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
# A reachable pose (rad): shoulder and elbow bent, wrist turned.
TIMESTEP_S = 0.001
TARGET = np.array([0.4, 0.6, -0.3, -1.2, 0.5, 0.8, -0.6])
KP = np.array([2000.0, 2000.0, 1000.0, 1000.0, 100.0, 50.0, 10.0])  # N·m/rad
KD = np.array([100.0, 100.0, 50.0, 50.0, 5.0, 2.0, 0.3])  # N·m·s/rad
MAX_EFFORT = np.array([320.0, 320.0, 176.0, 176.0, 110.0, 40.0, 40.0])  # N·m, the iiwa's


def load_kuka(sim: Client) -> list[str]:
    """Load the arm (fixed base) from its text; the daemon finds its meshes beside it.
    Return its revolute joints, base to flange."""
    sim.load_model("urdf", text=KUKA.read_text(), search_path=[KUKA.parent], fixed_base=True)
    return [joint.name for joint in sim.joints() if joint.type == "revolute"]


def reach(sim: Client, seconds: float) -> JointStates:
    """Hold TARGET from t = 0 for ``seconds``; return the joints' states then."""
    sim.reset("all")
    sim.set_params({"timestep": TIMESTEP_S})
    joints = load_kuka(sim)
    sim.set_joint_targets(joints, "position", TARGET, kp=KP, kd=KD, max_effort=MAX_EFFORT)
    final = sim.run_until_and_read_joints(seconds, joints)
    error = final.positions - TARGET
    print(f"{sim.status().engine}: after {final.sim_time:.2f} s, joint errors (rad) "
          f"{np.round(error, 4)}, max |error| {np.max(np.abs(error)):.4f} rad, "
          f"efforts (N·m) {np.round(final.efforts, 1)}")
    return final


def main(argv: list[str]) -> JointStates:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--seconds", type=float, default=3.0, help="sim time to hold")
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=30.0) as sim:
            return reach(sim, args.seconds)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as sim:
        return reach(sim, args.seconds)


if __name__ == "__main__":
    main(sys.argv[1:])
