"""Trials per minute on a pool of one daemon against a pool of two, in one run (issue 27).

Usage: python benchmarks/pool_scaling.py [--engine mujoco] [--board paper] [--balls 100]
           [--trials 8] [--max-sim-time 120] [--json FILE]

The same plan (one engine, one ball count, ``--trials`` repetitions) runs through
``galton.client.bench.pool_executor.run_pool`` on 1, then 2 embedded daemons started for it (meshed,
as ``bench --pool`` starts them); the wall time counts the trials only, not the daemons'
start. Prints trials per minute for each and their ratio. Target (issue 27): 2 daemons
≥ 1.7 × one daemon on a 2-core machine. Run it on a quiet machine: another process's load
moves the ratio.
"""

from __future__ import annotations

import argparse
import time

from common import machine, write_json

from galton.analysis.board import BoardSpec
from galton.client import Client
from galton.client.bench.daemons import embedded_mesh
from galton.client.bench.experiment import ExperimentConfig
from galton.client.bench.pool_executor import run_pool

POOL_SIZES = (1, 2)
TIMEOUT_S = 120.0


def trials_per_minute(size: int, config: ExperimentConfig) -> dict[str, float]:
    """Run the plan on ``size`` fresh daemons; the trials' wall time and their rate."""
    names = [f"pool-bench-{size}-{i + 1}" for i in range(size)]
    with embedded_mesh(dict.fromkeys(names, config.engines[0])) as session:
        clients = {name: Client(name, session=session, timeout=TIMEOUT_S) for name in names}
        try:
            started = time.perf_counter()
            results = run_pool(clients, config)
            wall = time.perf_counter() - started
        finally:
            for client in clients.values():
                client.close()
    trials = len(results.trials)
    return {"daemons": size, "trials": trials, "wall_s": wall,
            "trials_per_minute": 60.0 * trials / wall}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--board", default="paper")
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--trials", type=int, default=8)
    parser.add_argument("--max-sim-time", type=float, default=120.0)
    parser.add_argument("--json")
    args = parser.parse_args()
    config = ExperimentConfig(board=BoardSpec.load(args.board), engines=(args.engine,),
                              balls=(args.balls,), repetitions=args.trials,
                              max_sim_time=args.max_sim_time)
    rows = [trials_per_minute(size, config) for size in POOL_SIZES]
    ratio = rows[1]["trials_per_minute"] / rows[0]["trials_per_minute"]
    print(f"{machine()}; {args.engine}, board {args.board}, {args.balls} balls x "
          f"{args.trials} trials")
    for row in rows:
        print(f"{row['daemons']} daemon(s): {row['trials']} trials in {row['wall_s']:.1f} s, "
              f"{row['trials_per_minute']:.1f} trials/min")
    print(f"ratio 2 daemons / 1 daemon: {ratio:.2f} (target >= 1.7)")
    write_json(args.json, {"machine": machine(), "rows": rows, "ratio": ratio})


if __name__ == "__main__":
    main()
