"""How a trial's speed changes as its crowd of balls forms, in-process, chunk by chunk.

Usage: python benchmarks/crowd_steps.py [--balls 500] [--engines dart,mujoco]
                                        [--board paper-gazebo] [--chunk 0.05] [--chunks 8]

Builds the board and releases the balls as a bench trial does (the daemon's own ``World``
through ``LocalSim``, no bridge), then runs ``--chunks`` chunks of ``--chunk`` s of sim time
and prints each chunk's wall time and RTF. The bench's RTF is one figure per trial; this
shows where in the trial the time goes (DART's collapse once 500 balls pile into the
funnel, docs/PERFORMANCE.md).
"""

from __future__ import annotations

import argparse
import time

from local_sim import LocalSim

from galton.analysis.board import BallSpec, BoardSpec
from galton.client.bench.trial import PhysicsClock, TrialConfig, prepare_world, release


def chunks(engine: str, board_name: str, balls: int, chunk: float, count: int) -> None:
    board = BoardSpec.load(board_name)
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, balls))
    config = TrialConfig(engine, board)
    sim = LocalSim()
    shake, names = prepare_world(sim, config)
    release(sim, config, shake, names, PhysicsClock(sim))
    for index in range(count):
        started = time.perf_counter()
        stamp = sim.run_until((index + 1) * chunk)
        wall = time.perf_counter() - started
        print(f"{engine} {balls} balls: sim {stamp.sim_time:.2f} s, the last {chunk} s took "
              f"{wall:.2f} s wall (RTF {chunk / wall:.4f})", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, default=500)
    parser.add_argument("--engines", default="dart,mujoco")
    parser.add_argument("--board", default="paper-gazebo")
    parser.add_argument("--chunk", type=float, default=0.05)
    parser.add_argument("--chunks", type=int, default=8)
    args = parser.parse_args()
    for engine in args.engines.split(","):
        chunks(engine, args.board, args.balls, args.chunk, args.chunks)


if __name__ == "__main__":
    main()
