"""Joint reads, the 100 Hz mirror loop and a 1 kHz lockstep control loop (issue 24).

Usage: python benchmarks/joints.py [--reads 2000] [--mirror-seconds 10]
                                   [--lockstep-seconds 10] [--json FILE]

For each engine:
(a) ``get_joint_states`` of 100 joints (15 KUKA iiwa arms loaded, the first 100 of their 105
    joints) inside the daemon: the engine call alone and the whole operation (checks,
    engine, packing), timed in this process on a World like the daemon's; the same read
    through a daemon on loopback for comparison. Target: ≤ 1 ms inside the daemon.
(b) the mirror loop of examples/mirror_robot.py on loopback: at 100 Hz (paced by the wall
    clock), a 7-joint sample sent with set_joint_states reading the flange link's pose
    back in the same reply: one round trip per cycle. Target: p99 ≤ 2 ms.
(c) lockstep at 1 kHz: the KUKA at a 1 ms timestep; each cycle sets 7 position targets and
    steps once reading the 7 joints (set_joint_targets + step(1) with read_joints), as
    fast as it goes, for ``--lockstep-seconds`` of simulated time. Reported: the achieved
    rate (cycles per wall second; ≥ 1000 means a 1 kHz loop is sustained), cycle p50/p99,
    and the share of cycles longer than 1 ms.
The requests are sent in the raw protocol (``Client.call``).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data
from common import (
    ENGINES,
    daemon_client,
    machine,
    p50_p99,
    percentiles_ms,
    timed,
    write_json,
)

from galton.client import Client
from galton.daemon.engines import create_engine
from galton.daemon.ops.joints import get_joint_states
from galton.daemon.world.world import World
from galton.protocol import pack_f64, unpack_f64

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
KUKA_JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]
FLANGE = "lbr_iiwa_link_7"
ARMS, READ_JOINTS = 15, 100
KP = pack_f64(np.array([1000.0, 1500.0, 600.0, 600.0, 150.0, 60.0, 20.0]))
KD = pack_f64(np.array([20.0, 30.0, 10.0, 10.0, 2.0, 1.0, 0.2]))


def kuka_args(prefix: str = "") -> dict[str, Any]:
    return {"format": "urdf", "text": KUKA.read_text(), "search_path": str(KUKA.parent),
            "prefix": prefix}


def arm_names() -> list[str]:
    return [f"arm{a}/{j}" for a in range(ARMS) for j in KUKA_JOINTS][:READ_JOINTS]


# -- (a) reads of 100 joints -----------------------------------------------------------
def in_process_reads(engine: str, repeat: int) -> dict[str, Any]:
    world = World(create_engine(engine))
    try:
        for a in range(ARMS):
            world.load_model("urdf", KUKA.read_text(), None, f"arm{a}/",
                             search=[KUKA.parent])
        world.step(10)
        names = arm_names()
        engine_call = timed(lambda: world.engine.get_joint_states(names), repeat)
        operation = timed(lambda: get_joint_states(world, {"names": names}), repeat)
    finally:
        world.engine.close()
    return {"engine_call": percentiles_ms(engine_call), "operation": percentiles_ms(operation)}


def daemon_reads(sim: Client, repeat: int) -> dict[str, Any]:
    for a in range(ARMS):
        sim.call("load_model", kuka_args(f"arm{a}/"))
    sim.step(10)
    args = {"names": arm_names()}
    timed(lambda: sim.call("get_joint_states", args), 100)  # warm up
    return percentiles_ms(timed(lambda: sim.call("get_joint_states", args), repeat))


# -- (b) the 100 Hz mirror loop --------------------------------------------------------
def recording(cycles: int, seed: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """Seeded slow sinusoids within ±1 rad: positions and velocities (cycles, 7)."""
    rng = np.random.default_rng(seed)
    t = np.arange(cycles)[:, None] / 100.0
    amplitude, omega = rng.uniform(0.3, 1.0, 7), 2 * np.pi * rng.uniform(0.1, 0.8, 7)
    return amplitude * np.sin(omega * t), amplitude * omega * np.cos(omega * t)


def mirror(sim: Client, seconds: float) -> dict[str, Any]:
    sim.call("reset", {"scope": "all"})
    sim.call("load_model", kuka_args())
    cycles = round(seconds * 100)
    positions, velocities = recording(cycles)
    cycle = []
    start = time.perf_counter()
    for i in range(cycles):
        time.sleep(max(0.0, start + i / 100 - time.perf_counter()))  # the 100 Hz pace
        sent = time.perf_counter()
        result = sim.call("set_joint_states", {
            "names": KUKA_JOINTS, "positions": pack_f64(positions[i]),
            "velocities": pack_f64(velocities[i]), "read": [FLANGE]})
        cycle.append(time.perf_counter() - sent)
        assert unpack_f64(result["poses"], 7).shape == (1, 7)
    return percentiles_ms(cycle)


# -- (c) the 1 kHz lockstep loop -------------------------------------------------------
def lockstep(sim: Client, seconds: float) -> dict[str, Any]:
    sim.call("reset", {"scope": "all"})
    sim.call("set_params", {"params": {"timestep": 0.001}})
    sim.call("load_model", kuka_args())
    cycles = round(seconds * 1000)
    t = np.arange(1, cycles + 1)[:, None] * 0.001
    targets = 0.4 * np.sin(2 * np.pi * 0.5 * t + np.arange(7) * 0.5) - 0.4 * np.sin(
        np.arange(7) * 0.5)
    durations, errors = [], []
    started = time.perf_counter()
    for i in range(cycles):
        begun = time.perf_counter()
        sim.call("set_joint_targets", {"names": KUKA_JOINTS, "mode": "position",
                                       "targets": pack_f64(targets[i]), "kp": KP, "kd": KD})
        result = sim.call("step", {"count": 1, "read_joints": KUKA_JOINTS})
        durations.append(time.perf_counter() - begun)
        errors.append(unpack_f64(result["joints"]["positions"], 1).ravel() - targets[i])
    wall = time.perf_counter() - started
    settled = np.abs(np.array(errors[min(500, cycles // 2):]))
    return {**percentiles_ms(durations), "rate_hz": cycles / wall, "wall_s": wall,
            "over_1ms": float(np.mean(np.array(durations) > 1e-3)),
            "tracking_max_rad": float(settled.max())}


def measure(engine: str, args: argparse.Namespace) -> dict[str, Any]:
    result: dict[str, Any] = {"engine": engine, **in_process_reads(engine, args.reads)}
    with daemon_client(engine, telemetry_rate=10.0) as (_daemon, sim):
        result["daemon_read"] = daemon_reads(sim, args.reads)
        result["mirror"] = mirror(sim, args.mirror_seconds)
        result["lockstep"] = lockstep(sim, args.lockstep_seconds)
    return result


def print_tables(results: list[dict[str, Any]], args: argparse.Namespace) -> None:
    print(f"# joints on {machine()}, {time.strftime('%Y-%m-%d')}")
    print(f"| engine | get_joint_states of {READ_JOINTS}: engine call p50 / p99 | whole "
          "operation p50 / p99 | through the daemon p50 / p99 |")
    print("| --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {_pair(r['engine_call'])} | {_pair(r['operation'])} | "
              f"{_pair(r['daemon_read'])} |")
    print("\n| engine | mirror at 100 Hz: round trip p50 / p99 | lockstep 1 kHz: rate | "
          "cycle p50 / p99 | cycles > 1 ms |")
    print("| --- | --- | --- | --- | --- |")
    for r in results:
        lock, mir = r["lockstep"], r["mirror"]
        print(f"| {r['engine']} | {_pair(mir)} | {lock['rate_hz']:.0f} Hz | {_pair(lock)} | "
              f"{100 * lock['over_1ms']:.1f} % |")
    print(f"\n({args.reads} reads; mirror {args.mirror_seconds:g} s; lockstep "
          f"{args.lockstep_seconds:g} s of sim time; lockstep tracking error after 0.5 s: "
          + ", ".join(f"{r['engine']} {r['lockstep']['tracking_max_rad']:.3f} rad"
                      for r in results) + ")")


def _pair(p: dict[str, Any]) -> str:
    return f"{p50_p99(p, 3)} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--reads", type=int, default=2000)
    parser.add_argument("--mirror-seconds", type=float, default=10.0)
    parser.add_argument("--lockstep-seconds", type=float, default=10.0)
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(engine, args) for engine in args.engines.split(",")]
    print_tables(results, args)
    write_json(args.json, results)


if __name__ == "__main__":
    main()
