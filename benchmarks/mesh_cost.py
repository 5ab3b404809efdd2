"""What mesh collisions cost each engine: the paper board of primitives against the same
board as triangle meshes (``paper-mesh``), stepped in this process with the same balls.

For each engine, the two boards are built side by side (two engines of the same kind), the
balls spawned at the board's nominal release positions and let fall for WARM_UP_S, then the
two stepped in alternating
rounds of STEPS steps. Each round is timed in this process's CPU time (the engines step on
this one thread), which other jobs on a loaded machine disturb far less than wall time; the
figure is the ratio (mesh / primitives) within one run, not an absolute cost.

    python benchmarks/mesh_cost.py [--engines mujoco,pybullet,ode,dart] [--balls 25]
                                   [--rounds 5] [--steps 200]
"""

from __future__ import annotations

import argparse
import statistics
import time

from galton.analysis.board import BoardSpec
from galton.analysis.board_release import nominal_positions
from galton.client.bench.build import ball_group, ball_names, board_groups
from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine

WARM_UP_S = 1.0  # sim time before the timed rounds: the balls have reached the pins


def build(engine_name: str, board: str, balls: int) -> Engine:
    """An engine holding the board and its balls at their nominal release positions."""
    spec = BoardSpec.load(board)
    engine = create_engine(engine_name)
    if spec.engine_contacts(engine_name).params:  # the board's settings, as the bench sets
        engine.set_params(spec.engine_contacts(engine_name).params)
    engine.spawn(board_groups(spec, engine_name))
    positions = nominal_positions(spec, balls)
    engine.spawn([ball_group(spec, engine_name, ball_names(balls), positions)])
    engine.step(round(WARM_UP_S / engine.timestep))  # the balls among the pins
    return engine


def ratio(engine_name: str, balls: int, rounds: int, steps: int) -> tuple[float, float]:
    """Median CPU time per step of paper-mesh over paper's, and its min-max spread."""
    pair = {board: build(engine_name, board, balls) for board in ("paper", "paper-mesh")}
    ratios = []
    try:
        for _ in range(rounds):
            spent = {}
            for board, engine in pair.items():
                start = time.process_time()
                engine.step(steps)
                spent[board] = time.process_time() - start
            ratios.append(spent["paper-mesh"] / spent["paper"])
    finally:
        for engine in pair.values():
            engine.close()
    return statistics.median(ratios), max(ratios) - min(ratios)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="mujoco,pybullet,ode,dart")
    parser.add_argument("--balls", type=int, default=25)
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args()
    for name in args.engines.split(","):
        median, spread = ratio(name, args.balls, args.rounds, args.steps)
        print(f"{name}: paper-mesh / paper CPU time per step = {median:.2f} "
              f"(spread {spread:.2f} over {args.rounds} rounds of {args.steps} steps, "
              f"{args.balls} balls)")


if __name__ == "__main__":
    main()
