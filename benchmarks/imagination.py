"""Imagination (issue 51): the look-ahead at the engine's speed, and many futures in one
call, timed through a daemon over Zenoh on loopback.

Usage: python benchmarks/imagination.py [--engines mujoco,pybullet,ode,dart] [--balls 100]
                                        [--repeat 50] [--futures 8] [--horizon 1.0]
                                        [--rounds 3] [--json FILE]

For each engine, on a fresh daemon, a Galton world (the ``paper`` board's solids and
``--balls`` spheres released and stepped 0.2 s: moving and touching):
(a) ``snapshot`` into a slot, ``restore`` from it (the same structure: MuJoCo sets its
    kept state in place), ``fork_world`` (then deleted, not timed): p50 / p99 of the round
    trips. Targets on MuJoCo with 100 balls: 2 / 2 / 3 ms p50.
(b) ``--futures`` single predictions of ``--horizon`` s one after another, against one
    ``predict`` with ``futures`` N (``perturb`` position 1 mm, seed 1), sampling 10 balls
    every 0.1 s; the ratio (one call / N calls) per round, ``--rounds`` rounds, reported
    as median with its min..max. Target: ≤ 0.7 on MuJoCo (native threads, one per core the
    daemon may use: ``--limit future_threads``).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

from common import daemon_client, machine, p50_p99, percentiles_ms, timed, write_json

from galton.analysis.board import BallSpec, BoardSpec
from galton.analysis.board_release import release_schedule
from galton.client import Client
from galton.client.bench.build import ball_group, ball_names, board_groups


def galton_world(sim: Client, engine: str, balls: int) -> list[str]:
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, balls))
    sim.spawn(*board_groups(board, engine))
    names = ball_names(balls)
    sim.spawn(ball_group(board, engine, names, release_schedule(board, 0, balls).positions))
    sim.run_until(0.2)
    return list(names)


def look_ahead(sim: Client, repeat: int) -> dict[str, Any]:
    sim.snapshot("bench")
    out = {"snapshot": percentiles_ms(timed(lambda: sim.snapshot("bench"), repeat)),
           "restore": percentiles_ms(timed(lambda: sim.restore("bench"), repeat))}
    forks = []
    for _ in range(repeat):
        started = time.perf_counter()
        sim.fork_world("bench_fork")
        forks.append(time.perf_counter() - started)
        sim.delete_world("bench_fork")
    out["fork_world"] = percentiles_ms(forks)
    return out


def futures(sim: Client, names: list[str], count: int, horizon: float,
            rounds: int) -> dict[str, Any]:
    read = names[:10]
    ratios, singles, together = [], [], []
    for _ in range(rounds):
        started = time.perf_counter()
        for _ in range(count):
            sim.predict(horizon, every=0.1, read=read)
        single = time.perf_counter() - started
        started = time.perf_counter()
        found = sim.predict(horizon, every=0.1, read=read, futures=count,
                            perturb={"position": 0.001}, seed=1)
        many = time.perf_counter() - started
        assert found.futures == count
        singles.append(single)
        together.append(many)
        ratios.append(many / single)
    ratios.sort()
    return {"futures": count, "horizon_s": horizon, "single_s": singles,
            "futures_s": together, "ratio_median": ratios[len(ratios) // 2],
            "ratio_min": ratios[0], "ratio_max": ratios[-1]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--engines", default="mujoco,pybullet,ode,dart")
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--repeat", type=int, default=50)
    parser.add_argument("--futures", type=int, default=8)
    parser.add_argument("--horizon", type=float, default=1.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    report: dict[str, Any] = {"machine": machine(), "balls": args.balls, "engines": {}}
    print(f"{machine()}; {args.balls} balls; times p50 / p99 ms")
    for engine in args.engines.split(","):
        with daemon_client(engine, timeout=600.0) as (_, sim):
            names = galton_world(sim, engine, args.balls)
            ahead = look_ahead(sim, args.repeat)
            many = futures(sim, names, args.futures, args.horizon, args.rounds)
        report["engines"][engine] = {**ahead, "futures": many}
        print(f"{engine}: snapshot {p50_p99(ahead['snapshot'])}, restore "
              f"{p50_p99(ahead['restore'])}, fork_world {p50_p99(ahead['fork_world'])}; "
              f"{args.futures} futures of {args.horizon:g} s in one call / "
              f"{args.futures} single predictions: {many['ratio_median']:.2f} "
              f"({many['ratio_min']:.2f}..{many['ratio_max']:.2f})")
    write_json(args.json, report)


if __name__ == "__main__":
    main()
