"""Two parameter settings, trial against trial: speed, settling and, on MuJoCo, who stays awake.

Usage: python research/ab_trials.py ENGINE BALLS MODE REPS --a JSON --b JSON [--seed N]

e.g. python research/ab_trials.py mujoco 500 all-at-once 3 \\
         --a '{"mujoco.wake_balanced": true}' --b '{"mujoco.wake_balanced": false}'

Runs repetitions 0..REPS-1 of the paper board in-process (the daemon's World, as
``fidelity_inprocess.py`` does), alternating A and B on each repetition to spread the
machine's noise, and prints one line per trial: wall and sim time, sim/wall, the trial's
width, unsettled balls and, on MuJoCo, how many trees are still awake one simulated second
after the trial ended (a pile that never sleeps costs steps). Then sim/wall over all trials
of each side. Compare the two sides of one run only.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np
from fidelity_inprocess import board_for, width
from in_process import LocalSim

from galton.client.bench.trial import TrialConfig, run_trial

AFTER_S = 1.0  # sim time stepped after the trial before counting awake trees


def awake_trees(sim: LocalSim) -> int | None:
    """Trees MuJoCo still simulates AFTER_S after the trial; None on other engines."""
    assert sim.world is not None
    engine = sim.world.engine
    if engine.name != "mujoco":
        return None
    sim.world.step(round(AFTER_S / engine.timestep))
    return int(np.count_nonzero(engine.data.tree_asleep < 0))


def one_trial(engine: str, balls: int, mode: str, params: dict[str, Any], rep: int,
              seed: int) -> dict[str, Any]:
    sim = LocalSim()
    started = time.perf_counter()
    record = run_trial(sim, TrialConfig(engine, board_for(engine, balls, mode, params, {}),
                                        repetition=rep, seed=seed))
    wall = time.perf_counter() - started
    return {"rep": rep, "wall_s": round(wall, 2), "sim_s": record.sim_time,
            "sim_per_wall": round(record.sim_time / wall, 3), "width": width(record.counts),
            "unsettled": record.unsettled, "awake_after": awake_trees(sim)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine")
    parser.add_argument("balls", type=int)
    parser.add_argument("mode", choices=["all-at-once", "stream"])
    parser.add_argument("reps", type=int)
    parser.add_argument("--a", default="{}")
    parser.add_argument("--b", default="{}")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    sides = {"A": json.loads(args.a), "B": json.loads(args.b)}
    trials: dict[str, list[dict[str, Any]]] = {side: [] for side in sides}
    for rep in range(args.reps):
        for side, params in sides.items():
            row = one_trial(args.engine, args.balls, args.mode, params, rep, args.seed)
            trials[side].append(row)
            print(json.dumps({"side": side, **row}), flush=True)
    for side, params in sides.items():
        rows = trials[side]
        total = sum(r["sim_s"] for r in rows) / sum(r["wall_s"] for r in rows)
        print(f"{side} {json.dumps(params)}: sim/wall {total:.3f} over {len(rows)} trials")


if __name__ == "__main__":
    main()
