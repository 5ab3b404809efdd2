"""What ODE's near-callback costs at 500 balls: the share of each step spent making contact
joints (the space's pair search in C, the Python callback that notes each pair, then one
``dCollide`` and the joints per pair) against the whole step, on the paper board.

Usage: python benchmarks/ode_near_callback.py [--balls 500] [--seconds 2.0] [--timestep 0.004]

Prints one JSON line: wall seconds in collision and in the whole step, their ratio, the
candidate pairs handled and the microseconds each cost. A ratio taken within one run, so it
holds on a loaded machine (docs/PERFORMANCE.md).
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

from galton.analysis.board import BoardSpec
from galton.client.bench.build import ball_group, ball_names, board_groups
from galton.daemon.engines.ode.engine import OdeEngine


def ball_grid(count: int) -> np.ndarray:
    """Balls in layers of 3 x 50 above the funnel, 0.1 m apart."""
    k = np.arange(count)
    return np.column_stack([-2.45 + (k % 50) * 0.1, -0.1 + (k // 50 % 3) * 0.1,
                            5.8 + (k // 150) * 0.1])


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--balls", type=int, default=500)
    parser.add_argument("--seconds", type=float, default=2.0)
    parser.add_argument("--timestep", type=float, default=0.004)
    args = parser.parse_args()
    spec = BoardSpec.load("paper")
    engine = OdeEngine()
    engine.set_params({"timestep": args.timestep})
    engine.spawn(board_groups(spec, "ode"))
    engine.spawn([ball_group(spec, "ode", ball_names(args.balls), ball_grid(args.balls))])
    collider, spent = engine._collider, [0.0]
    collide = collider.collide

    def timed(recording: bool) -> None:
        start = time.perf_counter()
        collide(recording)
        spent[0] += time.perf_counter() - start

    collider.collide = timed  # type: ignore[method-assign]
    steps = round(args.seconds / args.timestep)
    start = time.perf_counter()
    engine.step(steps)
    total = time.perf_counter() - start
    pairs = collider.pairs
    print(json.dumps({"balls": args.balls, "steps": steps, "timestep": args.timestep,
                      "step_s": round(total, 3), "collision_s": round(spent[0], 3),
                      "collision_share": round(spent[0] / total, 3), "pairs": pairs,
                      "us_per_pair": round(1e6 * spent[0] / max(pairs, 1), 2),
                      "rtf": round(args.seconds / total, 3)}))
    engine.close()


if __name__ == "__main__":
    main()
