"""What spreading an ensemble of futures over Ray actors gives: futures per second against
the number of actors, and the same futures bit for bit (issue 52, "futures too").

Usage: python benchmarks/ray_futures.py [--engine mujoco] [--balls 40] [--futures 256]
           [--horizon 0.5] [--actors 1,2,4] [--cpus-per-daemon 1] [--json FILE]

A pile of ``--balls`` spheres falling on a plane, on one embedded daemon (the source). The
ensemble (``--futures``, perturbed, seed 1) runs first on that daemon alone
(``LocalFutures``: batches of 64 one after another), then on a local Ray instance with
each count of ``--actors`` (``RayFutures``). Each row's wall time counts the ensemble only,
after one untimed ensemble that starts the actors and restores the snapshot; the Ray
instance's start and the actors' starts are timed apart. Prints each row (futures per
second, speed-up over the one daemon) and whether every row's futures, spread and scores
equal the one daemon's bit for bit. Run it on a quiet machine with as many cores as the
largest actor count asks (the ``device`` machine: ``--actors 1,2,4,8,15``).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np
import ray
from common import machine, write_json

from galton.client import Client, EmbeddedDaemon, plane, spheres
from galton.client.bench.futures import FutureRunner, LocalFutures, Start, predict_ensemble
from galton.client.bench.futures import start_of as snapshot_start
from galton.client.bench.ray_executor import RaySettings
from galton.client.bench.ray_futures import ray_futures
from galton.client.sdk.values import Prediction

TIMEOUT_S = 300.0
PERTURB = {"position": 0.001, "velocity": 0.01}


def pile(sim: Client, balls: int) -> list[str]:
    """A plane and a column of spheres just touching: contacts from the first steps."""
    sim.spawn(plane())
    names = [f"ball_{i}" for i in range(balls)]
    sim.spawn(spheres(names, [[0.01 * (i % 5), 0.01 * (i % 3), 0.05 + 0.1 * i]
                              for i in range(balls)], 0.05))
    return names


def timed(runner: FutureRunner, start: Start, args: argparse.Namespace, names: list[str]
          ) -> tuple[float, Prediction]:
    """One untimed ensemble (actors warm, snapshot restored), then one timed."""
    ask: dict[str, Any] = {"perturb": PERTURB, "seed": 1, "read": names,
                           "every": args.horizon / 5}
    predict_ensemble(runner, start, args.horizon, args.futures, **ask)
    began = time.perf_counter()
    found = predict_ensemble(runner, start, args.horizon, args.futures, **ask)
    return time.perf_counter() - began, found


def same(a: Prediction, b: Prediction) -> bool:
    return all(np.array_equal(getattr(a, k), getattr(b, k))
               for k in ("poses", "twists", "spread"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--balls", type=int, default=40)
    parser.add_argument("--futures", type=int, default=256)
    parser.add_argument("--horizon", type=float, default=0.5)
    parser.add_argument("--actors", default="1,2,4")
    parser.add_argument("--cpus-per-daemon", type=float, default=1.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    counts = [int(c) for c in args.actors.split(",")]
    rows: list[dict[str, Any]] = []
    with EmbeddedDaemon(args.engine, instance="futures-source").start() as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=TIMEOUT_S) as sim:
        names = pile(sim, args.balls)
        sim.step(10)
        start = snapshot_start(sim)
        local = LocalFutures(sim)
        wall, reference = timed(local, start, args, names)
        local.close()
        rows.append({"runner": "one daemon", "actors": 0, "start_s": 0.0, "wall_s": wall})
        began = time.perf_counter()
        ray.init(address="local", include_dashboard=False, log_to_driver=False,
                 num_cpus=max(counts) * args.cpus_per_daemon)
        ray_start = time.perf_counter() - began
        agree = True
        try:
            for count in counts:
                began = time.perf_counter()
                with ray_futures(RaySettings("local", args.cpus_per_daemon, count),
                                 args.engine, TIMEOUT_S, count) as runner:
                    started = time.perf_counter() - began
                    wall, found = timed(runner, start, args, names)
                agree &= same(found, reference)
                rows.append({"runner": f"ray x{count}", "actors": count, "start_s": started,
                             "wall_s": wall})
        finally:
            ray.shutdown()
    report(args, rows, ray_start, agree)


def report(args: argparse.Namespace, rows: list[dict[str, Any]], ray_start: float,
           agree: bool) -> None:
    base = rows[0]["wall_s"]
    print(f"{machine()}; {args.engine}, {args.balls} balls, {args.futures} futures of "
          f"{args.horizon:g} s")
    print(f"Ray instance start (ray.init, local): {ray_start:.1f} s")
    for row in rows:
        row["futures_per_s"] = args.futures / row["wall_s"]
        row["speedup"] = base / row["wall_s"]
        print(f"{row['runner']:>11}: actors' start {row['start_s']:.1f} s, ensemble in "
              f"{row['wall_s']:.2f} s, {row['futures_per_s']:.1f} futures/s, "
              f"x{row['speedup']:.2f} over one daemon")
    print(f"same futures, spread bit for bit on every row: {'yes' if agree else 'NO'}")
    write_json(args.json, {"machine": machine(), "ray_start_s": ray_start, "same": agree,
                           "rows": rows})


if __name__ == "__main__":
    main()
