"""Ahead of reality (issue 25): snapshots, forks and predictions, timed through a daemon.

Usage: python benchmarks/ahead.py [--engines mujoco,pybullet] [--repeat 20]
                                  [--seconds 10] [--json FILE]

For each engine, on a fresh daemon on loopback (times are round trips: request, the
daemon's work, reply):
(a) a 500-ball Galton world (the ``paper`` board's static solids and 500 spheres released
    and stepped 0.2 s, so they are moving and touching): ``snapshot`` into a slot,
    ``restore`` from it, and a snapshot returned as a blob; the blob's size in all and
    per body. Targets: snapshot and restore ≤ 5 ms each.
(b) ``fork_world`` of that world (then deleted, not timed). Target ≤ 20 ms.
(c) a 1 s ``predict`` of a KUKA iiwa holding position targets with 50 objects (spheres and
    boxes) falling around it, sampling the flange, the objects and the 7 joints every
    10 ms. Target ≤ 50 ms of wall time (≥ 20× real time).
(d) the same world playing at RTF 1.0 for ``--seconds``, first alone, then with (c)'s
    predictions back to back from another thread: the live world's achieved RTF (from its
    telemetry) and the p50/p99 of a control call (``set_joint_targets`` on the 7 joints,
    at 100 Hz). Target: RTF within ±2 %, the control call's p99 kept.
"""

from __future__ import annotations

import argparse
import threading
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

from galton.analysis.board import BallSpec, BoardSpec
from galton.analysis.board_release import release_schedule
from galton.client import Client, Telemetry, boxes, plane, spheres
from galton.client.bench.build import ball_group, ball_names, board_groups

BALLS = 500
OBJECTS = 50
KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]
FLANGE = "lbr_iiwa_link_7"
KP = np.array([1000.0, 1500.0, 600.0, 600.0, 150.0, 60.0, 20.0])
KD = np.array([20.0, 30.0, 10.0, 10.0, 2.0, 1.0, 0.2])
CONTROL_HZ = 100.0
TELEMETRY_HZ = 10.0


# -- (a), (b) the Galton world --------------------------------------------------------------
def galton_world(sim: Client, engine: str) -> int:
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, BALLS))
    sim.load_world(engine, board.engine_contacts(engine).params or None)  # its settings
    sim.spawn(*board_groups(board, engine))
    sim.spawn(ball_group(board, engine, ball_names(BALLS),
                         release_schedule(board, 0, BALLS).positions))
    sim.run_until(0.2)
    return sim.status().entity_count


def snapshots(sim: Client, engine: str, repeat: int) -> dict[str, Any]:
    bodies = galton_world(sim, engine)
    blob = sim.snapshot(blob=True)
    result = {"bodies": bodies, "blob_bytes": blob.nbytes,
              "bytes_per_body": blob.nbytes / bodies,
              "bytes_per_ball": (blob.nbytes - _board_bytes(sim, engine)) / BALLS,
              "snapshot": percentiles_ms(timed(lambda: sim.snapshot("bench"), repeat)),
              "snapshot_blob": percentiles_ms(timed(lambda: sim.snapshot(blob=True), repeat)),
              "restore": percentiles_ms(timed(lambda: sim.restore("bench"), repeat))}
    fork_times = []
    for _ in range(repeat):
        started = time.perf_counter()
        sim.fork_world("fork")
        fork_times.append(time.perf_counter() - started)
        sim.delete_world("fork")
    result["fork"] = percentiles_ms(fork_times)
    sim.delete_snapshot("bench")
    return result


def _board_bytes(sim: Client, engine: str) -> int:
    """The blob of the board alone (no ball), in a side world."""
    paper = BoardSpec.load("paper")
    sim.create_world("board", params=paper.engine_contacts(engine).params or None)
    try:
        board = sim.world("board")
        board.spawn(*board_groups(paper, engine))
        return board.snapshot(blob=True).nbytes
    finally:
        sim.delete_world("board")


# -- (c), (d) the KUKA with 50 objects --------------------------------------------------------
def kuka_world(sim: Client) -> list[str]:
    sim.load_world(sim.status().engine)
    sim.spawn(plane())
    sim.load_model("urdf", text=KUKA.read_text(), search_path=[KUKA.parent], fixed_base=True)
    rng = np.random.default_rng(25)
    ring = rng.uniform(0.4, 0.9, OBJECTS) * np.exp(1j * rng.uniform(0, 2 * np.pi, OBJECTS))
    xyz = np.column_stack([ring.real, ring.imag, rng.uniform(0.1, 1.0, OBJECTS)])
    half = OBJECTS // 2
    balls, crates = [f"ball_{i}" for i in range(half)], [f"crate_{i}" for i in range(half)]
    sim.spawn(spheres(balls, xyz[:half], 0.04))
    sim.spawn(boxes(crates, xyz[half:], [0.03, 0.03, 0.03]))
    sim.set_joint_targets(JOINTS, "position", [0.3, -0.4, 0.2, 0.8, 0.0, -0.5, 0.1],
                          kp=KP, kd=KD)
    return [FLANGE, *balls, *crates]


def predict_once(sim: Client, read: list[str]) -> None:
    sim.predict(1.0, every=0.01, read=read, read_joints=JOINTS)


def predictions(sim: Client, repeat: int) -> dict[str, Any]:
    read = kuka_world(sim)
    samples = timed(lambda: predict_once(sim, read), repeat)
    return {"predict_1s": percentiles_ms(samples),
            "times_real_time": 1.0 / float(np.median(samples))}


def live_under_predictions(sim: Client, seconds: float, with_predictions: bool) -> dict[str, Any]:
    read = kuka_world(sim)
    done = threading.Event()
    made = [0]

    def predict_back_to_back() -> None:
        while not done.is_set():
            predict_once(sim, read)
            made[0] += 1

    worker = threading.Thread(target=predict_back_to_back) if with_predictions else None
    received: list[Telemetry] = []
    with sim.on_telemetry(received.append):
        sim.play(1.0)
        if worker is not None:
            worker.start()
        calls = control_calls(sim, seconds)
    samples = [s for s in received if s.world == "default" and s.state == "playing"]
    done.set()
    if worker is not None:
        worker.join()
    sim.pause()
    first, last = samples[0], samples[-1]
    rtf = (last.sim_time - first.sim_time) / (last.wall_time - first.wall_time)
    return {"predictions": made[0], "achieved_rtf": rtf, "control": percentiles_ms(calls)}


def control_calls(sim: Client, seconds: float) -> list[float]:
    """set_joint_targets at 100 Hz (paced by the wall clock) for ``seconds``."""
    targets = np.array([0.3, -0.4, 0.2, 0.8, 0.0, -0.5, 0.1])
    out = []
    start = time.perf_counter()
    for i in range(int(seconds * CONTROL_HZ)):
        time.sleep(max(0.0, start + i / CONTROL_HZ - time.perf_counter()))  # the pace
        sent = time.perf_counter()
        sim.set_joint_targets(JOINTS, "position", targets + 0.01 * np.sin(i / 50), kp=KP, kd=KD)
        out.append(time.perf_counter() - sent)
    return out


def measure(engine: str, repeat: int, seconds: float) -> dict[str, Any]:
    with daemon_client(engine, telemetry_rate=TELEMETRY_HZ) as (_, sim):
        result: dict[str, Any] = {"engine": engine, **snapshots(sim, engine, repeat)}
        result.update(predictions(sim, max(5, repeat // 2)))
        result["alone"] = live_under_predictions(sim, seconds, False)
        result["with_predictions"] = live_under_predictions(sim, seconds, True)
        return result


def report(results: list[dict[str, Any]]) -> None:
    print("| engine | bodies | blob (bytes) | per body | per ball | snapshot p50/p99 (ms) | "
          "restore p50/p99 (ms) | fork p50/p99 (ms) | 1 s predict p50/p99 (ms) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in results:
        cells = [p50_p99(r[k]) for k in ("snapshot", "restore", "fork", "predict_1s")]
        print(f"| {r['engine']} | {r['bodies']} | {r['blob_bytes']} | "
              f"{r['bytes_per_body']:.0f} | {r['bytes_per_ball']:.0f} | " + " | ".join(cells)
              + " |")
    print()
    print("| engine | live world | achieved RTF | predictions made | control p50 (ms) | "
          "control p99 (ms) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in results:
        for key, label in (("alone", "alone"), ("with_predictions", "predictions back to back")):
            row = r[key]
            print(f"| {r['engine']} | {label} | {row['achieved_rtf']:.4f} | "
                  f"{row['predictions']} | {row['control']['p50']:.2f} | "
                  f"{row['control']['p99']:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(e, args.repeat, args.seconds) for e in args.engines.split(",")]
    print(f"# ahead of reality on {machine()}: {BALLS}-ball Galton world, KUKA + {OBJECTS} "
          f"objects, {args.seconds:g} s at RTF 1.0 per phase")
    report(results)
    write_json(args.json, results)


if __name__ == "__main__":
    main()
