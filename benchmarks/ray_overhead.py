"""What running the bench on Ray costs: the same trials plainly, on a pool and on Ray, in one
run (issue 52).

Usage: python benchmarks/ray_overhead.py [--engine mujoco] [--board paper] [--balls 30]
           [--trials 8] [--workers 2] [--cpus-per-daemon 1] [--json FILE]

The same plan (one engine, one ball count, ``--trials`` repetitions) runs through the one
executor seam (``galton.client.bench.executor``) four ways: plainly on one daemon (plain
``bench``); through Ray on one actor (what Ray adds to each trial); on a pool of
``--workers`` embedded daemons (``bench --pool``) and on as many Ray actors (``bench --ray
local``). The wall times count the trials only, after one untimed trial per worker; the
starts are timed apart: the Ray instance (``ray.init``, once), the actors with their
daemons, the pool's daemons. Prints each row, the ratios (Ray on 1 actor / plain, Ray on N
actors / pool of N, and each against the plain run) and whether every row gave the same
bins trial for trial. Run it on a quiet machine: another process's load moves the ratios.
Ray's token authentication is left on as Ray sets it (``RAY_AUTH_MODE=disabled`` in the
environment opts out).
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import ray
from common import machine, write_json

from galton.analysis.board import BoardSpec
from galton.analysis.records import ExperimentResults
from galton.client import Client
from galton.client.bench.daemons import embedded_mesh
from galton.client.bench.executor import Executor, LocalExecutor
from galton.client.bench.experiment import ExperimentConfig, run_plan
from galton.client.bench.pool_executor import PoolExecutor
from galton.client.bench.ray_executor import RaySettings, ray_executor

TIMEOUT_S = 120.0


def timed_plan(label: str, executor: Executor, config: ExperimentConfig,
               started_s: float) -> dict[str, Any]:
    """Run the plan through ``executor``, after one untimed trial per worker (a first trial
    pays for loading the engine); its row (``started_s``: its workers' start)."""
    run_plan(executor, replace(config, repetitions=len(executor.workers())))
    began = time.perf_counter()
    results = run_plan(executor, config)
    wall = time.perf_counter() - began
    return {"executor": label, "workers": len(executor.workers()), "start_s": started_s,
            "trials": len(results.trials), "wall_s": wall,
            "trials_per_minute": 60.0 * len(results.trials) / wall,
            "bins": [t.counts for t in results.trials], "results": results}


def on_daemons(label: str, size: int, config: ExperimentConfig,
               make: Callable[[dict[str, Client]], Executor]) -> dict[str, Any]:
    """The plan on ``size`` fresh embedded daemons (meshed, as ``bench --pool`` starts them)."""
    names = [f"{label}-{i + 1}" for i in range(size)]
    began = time.perf_counter()
    with embedded_mesh(dict.fromkeys(names, config.engines[0])) as session:
        clients = {name: Client(name, session=session, timeout=TIMEOUT_S) for name in names}
        start = time.perf_counter() - began
        try:
            return timed_plan(label, make(clients), config, start)
        finally:
            for client in clients.values():
                client.close()


def on_ray(actors: int, cpus: float, config: ExperimentConfig) -> dict[str, Any]:
    """The plan on ``actors`` Ray actors of the running instance."""
    began = time.perf_counter()
    with ray_executor(RaySettings("local", cpus, actors), config.engines[0], TIMEOUT_S,
                      actors) as executor:
        return timed_plan(f"ray x{actors}", executor, config, time.perf_counter() - began)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--board", default="paper")
    parser.add_argument("--balls", type=int, default=30)
    parser.add_argument("--trials", type=int, default=8)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--cpus-per-daemon", type=float, default=1.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    config = ExperimentConfig(board=BoardSpec.load(args.board), engines=(args.engine,),
                              balls=(args.balls,), repetitions=args.trials)
    plain = on_daemons("plain", 1, config,
                       lambda clients: LocalExecutor({args.engine: next(iter(clients.values()))}))
    pool = on_daemons("pool", args.workers, config, PoolExecutor)
    began = time.perf_counter()
    ray.init(address="local", include_dashboard=False, log_to_driver=False,
             num_cpus=max(args.workers, 1) * args.cpus_per_daemon)
    ray_start = time.perf_counter() - began
    try:
        ray_one = on_ray(1, args.cpus_per_daemon, config)
        ray_many = on_ray(args.workers, args.cpus_per_daemon, config)
    finally:
        ray.shutdown()
    rows = [plain, ray_one, pool, ray_many]
    report(args, rows, ray_start)


def report(args: argparse.Namespace, rows: list[dict[str, Any]], ray_start: float) -> None:
    plain, ray_one, pool, ray_many = rows
    same = all(row["bins"] == plain["bins"] for row in rows)
    ratios = {"ray_1_over_plain": ray_one["wall_s"] / plain["wall_s"],
              "ray_n_over_pool_n": ray_many["wall_s"] / pool["wall_s"],
              "pool_n_over_plain": pool["wall_s"] / plain["wall_s"],
              "ray_n_over_plain": ray_many["wall_s"] / plain["wall_s"]}
    print(f"{machine()}; {args.engine}, board {args.board}, {args.balls} balls x "
          f"{args.trials} trials, {args.workers} workers of {args.cpus_per_daemon:g} CPU(s)")
    print(f"Ray instance start (ray.init, local): {ray_start:.1f} s")
    for row in rows:
        print(f"{row['executor']:>8} ({row['workers']} worker(s)): start {row['start_s']:.1f} s, "
              f"{row['trials']} trials in {row['wall_s']:.1f} s, "
              f"{row['trials_per_minute']:.1f} trials/min")
    print("wall-time ratios (trials only): " + ", ".join(
        f"{name.replace('_', ' ')} {value:.2f}" for name, value in ratios.items()))
    print(f"same bins trial for trial on every row: {'yes' if same else 'NO'}")
    results: ExperimentResults = ray_many["results"]
    print(f"executor recorded: {results.executor}")
    write_json(args.json, {"machine": machine(), "ray_start_s": ray_start, "ratios": ratios,
                           "same_bins": same,
                           "rows": [{k: v for k, v in row.items() if k != "results"}
                                    for row in rows]})


if __name__ == "__main__":
    main()
