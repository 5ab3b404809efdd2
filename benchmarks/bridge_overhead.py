"""What the bridge costs: the same Galton trial through a daemon and in-process.

Usage: python benchmarks/bridge_overhead.py [--balls 100] [--rounds 3] [--engines LIST]
                                           [--json FILE]

The in-process side drives the daemon's own ``World`` over the same engine with exactly the
requests a trial sends (spawn, then run until the balls rest, checked every 0.5 s), so the only
difference is Zenoh, msgpack and the physics thread hand-off; the script checks that both
sides simulated the identical trial (same sim time, same bins). Runs
alternate (in-process, bridge, ...) to spread the machine's noise; the ratios of the
medians and of the minima (the least disturbed run of each) are reported.
Target (issue 6): bridge ≤ 1.05 × in-process wall time.
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

from common import ENGINES, daemon_client, machine, write_json
from local_sim import LocalSim

from galton.analysis.board import BallSpec, BoardSpec, EngineContacts
from galton.client.bench.trial import TrialConfig, run_trial


def trial_config(engine: str, balls: int, params: dict[str, Any] | None = None) -> TrialConfig:
    """Repetition 0 of the paper board with this many balls, with its materials plus
    ``params``."""
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, balls))
    if params:
        own = board.contacts[engine]
        board = board.replace(contacts={**board.contacts, engine: EngineContacts(
            params={**own.params, **params}, bodies=dict(own.bodies))})
    return TrialConfig(engine, board, repetition=0, seed=0)


def wall(sim: Any, config: TrialConfig) -> tuple[float, float, list[int]]:
    started = time.perf_counter()
    record = run_trial(sim, config)
    return time.perf_counter() - started, record.sim_time, record.counts


def measure(engine: str, balls: int, rounds: int) -> dict:
    config = trial_config(engine, balls)
    local_walls, bridge_walls = [], []
    with daemon_client(engine) as (_, sim):
        _, bridge_time, bridge_counts = wall(sim, config)  # warm both paths once
        _, local_time, local_counts = wall(LocalSim(), config)
        if (bridge_time, bridge_counts) != (local_time, local_counts):
            raise SystemExit(f"{engine}: the two sides simulated different trials")
        for _ in range(rounds):
            local_walls.append(wall(LocalSim(), config)[0])
            bridge_walls.append(wall(sim, config)[0])
    local, bridge = statistics.median(local_walls), statistics.median(bridge_walls)
    return {"engine": engine, "balls": balls, "rounds": rounds, "local_s": local_walls,
            "bridge_s": bridge_walls, "ratio": bridge / local,
            "ratio_of_minima": min(bridge_walls) / min(local_walls)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--engines", default=",".join(ENGINES),
                        help="e.g. mujoco,pybullet,ode,dart")
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(engine, args.balls, args.rounds) for engine in args.engines.split(",")]
    print(f"# bridge overhead on {machine()}: paper board, {args.balls} balls, "
          f"{args.rounds} alternating rounds")
    print("| engine | in-process median / min (s) | through the bridge median / min (s) | "
          "ratio of medians | ratio of minima |")
    print("| --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {statistics.median(r['local_s']):.3f} / {min(r['local_s']):.3f}"
              f" | {statistics.median(r['bridge_s']):.3f} / {min(r['bridge_s']):.3f} | "
              f"{r['ratio']:.3f} | {r['ratio_of_minima']:.3f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
