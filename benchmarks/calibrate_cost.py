"""What calibrate costs (issue 53), through a daemon per engine.

Usage: python benchmarks/calibrate_cost.py [--engines mujoco,pybullet,ode,dart]
                                           [--predictions 200] [--threads 1,2]
                                           [--json FILE]

For each engine, on a fresh daemon on loopback: the bar's scene (a box pushed at 1.5 m/s
across a heavy slab at friction 0.3, a ball dropped on it at restitution 0.5; the slab's
surface per engine as docs/PHYSICS.md, "Calibration"), 1 s of it predicted and sampled at
60 Hz as the observation, then the world set to 0.8 and 0.1 and both fitted back with
``--predictions`` predictions: the wall time of the fit, the predictions per second, the
values found and the error before and after, and the batches of futures they ran in. Each
batch (a generation of candidates) is one set of futures (daemon/core/candidates.py),
stepped together: on MuJoCo on ``future_threads`` native threads, measured for each of
``--threads`` (the daemon's ``--limit future_threads=N``); the other engines step their
futures one after another, so the time is about predictions x (a fork + 1 s of steps).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
from common import daemon_client, machine, write_json

from galton.client import Client, boxes, plane, spheres

SURFACE = {"mujoco": (0.0, 0.5), "pybullet": (1.0, 1.0), "dart": (1.0, 1.0), "ode": (0.0, 0.0)}
FIT = {"box.friction": (0.05, 1.5), "ball.restitution": (0.0, 0.95)}


def scene(sim: Client, engine: str) -> list[str]:
    friction, restitution = SURFACE[engine]
    sim.spawn(plane())
    sim.spawn(boxes(["slab"], [[0.5, 0.0, 0.05]], [1.5, 0.6, 0.05], mass=500.0,
                    friction=friction, restitution=restitution))
    sim.spawn(boxes(["box"], [[0.0, -0.3, 0.15]], [0.05, 0.05, 0.05], mass=1.0,
                    friction=0.3))
    sim.spawn(spheres(["ball"], [[0.5, 0.3, 3.0]], 0.05, mass=0.2, restitution=0.5))
    sim.step(round(0.5 / sim.status().timestep))
    twist = np.zeros((1, 6))
    twist[0, 0] = 1.5
    sim.set_states(["box"], sim.get_states(["box"]).poses, twist)
    return ["box", "ball"]


def measure(engine: str, predictions: int, threads: int) -> dict[str, Any]:
    with daemon_client(engine, extra_args=["--limit", f"future_threads={threads}"]) as (_, sim):
        sim.load_world(engine)
        moving = scene(sim, engine)
        seen = sim.predict(1.0, every=1 / 60, read=moving)
        sim.update(["box"], friction=0.8)
        sim.update(["ball"], restitution=0.1)
        started = time.perf_counter()
        fit = sim.calibrate(FIT, moving, seen.times, seen.poses, twists=seen.twists[0],
                            max_predictions=predictions)
        seconds = time.perf_counter() - started
    return {"engine": engine, "threads": threads, "seconds": seconds,
            "predictions": fit.predictions, "batches": fit.batches,
            "predictions_per_s": fit.predictions / seconds, "fitted": fit.fitted,
            "error_before_m": fit.error_before, "error_after_m": fit.error_after}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="mujoco,pybullet,ode,dart")
    parser.add_argument("--predictions", type=int, default=200)
    parser.add_argument("--threads", default="1,2", help="future_threads to try (MuJoCo)")
    parser.add_argument("--json")
    args = parser.parse_args()
    print(machine())
    rows = []
    counts = [int(n) for n in args.threads.split(",")]
    for engine in args.engines.split(","):
        for threads in counts if engine == "mujoco" else counts[:1]:
            row = measure(engine, args.predictions, threads)
            rows.append(row)
            report(row)
    write_json(args.json, rows)


def report(row: dict[str, Any]) -> None:
    fitted = ", ".join(f"{k} {v:.3f}" for k, v in row["fitted"].items())
    print(f"{row['engine']} ({row['threads']} future threads): {row['predictions']} "
          f"predictions in {row['batches']} batches of futures, {row['seconds']:.1f} s "
          f"({row['predictions_per_s']:.1f}/s); {fitted}; error "
          f"{row['error_before_m'] * 1e3:.1f} -> {row['error_after_m'] * 1e3:.2f} mm")


if __name__ == "__main__":
    main()
