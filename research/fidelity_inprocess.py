"""Fidelity of one setting, in-process: the bench's trial loop over the daemon's own World.

Usage: python research/fidelity_inprocess.py ENGINE BALLS REPS MODE
           [--params JSON] [--surfaces JSON] [--seed N]

e.g. python research/fidelity_inprocess.py mujoco 500 10 all-at-once \\
         --params '{"mujoco.condim": 6}' \\
         --surfaces '{"ball": {"friction": 0.5, "restitution": 0.1}}'

The calibration runs in docs/physics/mujoco.md came from this loop. No Zenoh is involved,
and a trial here is bit-identical to the same trial through a daemon
(benchmarks/bridge_overhead.py checks that; ``LocalSim`` is benchmarks/local_sim.py).
``--params`` sets daemon parameters over the board's (``default_*`` reach no board body:
each carries the board's material); ``--surfaces`` sets per-role surfaces over the board's
(roles: ball, pin, funnel, divider, wall, glass, floor). The script prints one JSON line:
the pooled width (standard deviation of the bin index; the binomial's is 1.658), the Monte
Carlo p, the median per-trial chi-squared, lost and unsettled balls, the median RTF and sim
time of a trial, each trial's width, and the pooled counts.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import statistics

import numpy as np
from in_process import LocalSim

from galton.analysis import shape, stats
from galton.analysis.board import BallSpec, BoardSpec, EngineContacts, SurfaceSpec
from galton.client.bench.trial import TrialConfig, run_trial


def board_for(engine: str, balls: int, mode: str, params: dict, surfaces: dict) -> BoardSpec:
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, balls),
                          release=dataclasses.replace(board.release, mode=mode))
    own = board.contacts[engine]  # the board's materials, changed by these
    contacts = EngineContacts(params={**own.params, **params}, bodies={
        **own.bodies, **{k: SurfaceSpec(**v) for k, v in surfaces.items()}})
    return board.replace(contacts={**board.contacts, engine: contacts})


def width(counts: np.ndarray | list[int]) -> float:
    """The standard deviation of the bin index over these balls (the binomial's: 1.658)."""
    return round(shape.width(counts), 3)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine")
    parser.add_argument("balls", type=int)
    parser.add_argument("reps", type=int)
    parser.add_argument("mode", choices=["all-at-once", "stream"])
    parser.add_argument("--params", default="{}")
    parser.add_argument("--surfaces", default="{}")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    board = board_for(args.engine, args.balls, args.mode, json.loads(args.params),
                      json.loads(args.surfaces))
    records = [run_trial(LocalSim(), TrialConfig(args.engine, board, repetition=rep,
                                                 seed=args.seed))
               for rep in range(args.reps)]
    pooled = np.sum([r.counts for r in records], axis=0)
    print(json.dumps({
        "engine": args.engine, "balls": args.balls, "reps": args.reps, "mode": args.mode,
        "params": json.loads(args.params), "surfaces": json.loads(args.surfaces),
        "seed": args.seed,
        "width": width(pooled),
        "p_mc": round(stats.p_monte_carlo(
            pooled, draws=stats.DEFAULT_DRAWS * stats.POOLED_DRAWS_FACTOR), 3),
        "median_chi2": round(statistics.median(stats.chi2_statistic(r.counts)
                                               for r in records), 2),
        "lost": sum(r.lost for r in records), "unsettled": sum(r.unsettled for r in records),
        "rtf_median": round(statistics.median(r.rtf or 0.0 for r in records), 2),
        "sim_time_median": round(statistics.median(r.sim_time for r in records), 1),
        "trial_widths": [width(r.counts) for r in records],
        "pooled": pooled.tolist()}))


if __name__ == "__main__":
    main()
