"""An arm that imagines before it acts: pybullet_data's KUKA iiwa picks, of N candidate
plans, the one whose flange ends nearest a goal, by imagining all of them in ONE predict
call (``plans``, one per future, and a ``score``: the flange's distance to the goal at the
horizon), then executes the chosen plan live, and finds the flange where it imagined it.

Each plan is two timed joint-space targets (a waypoint at 0 s, the final pose at half
the horizon) held by the engine's PD law. The candidates are drawn around a reaching pose
with a seeded generator, so a run is repeatable. Executed live, the plan's targets are sent
at the same steps it was imagined with, and on MuJoCo and PyBullet the flange lands on the
imagined spot bit for bit (the prediction is the same physics, not a model of it).

Starts its own daemon on a free loopback port unless --connect is given:
python examples/imagine_plans.py [--engine mujoco|pybullet] [--plans N] [--horizon S]
                                 [--connect ENDPOINT --instance NAME]
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pybullet_data

from galton.client import Client, EmbeddedDaemon

KUKA = Path(pybullet_data.getDataPath()) / "kuka_iiwa" / "model.urdf"
FLANGE = "lbr_iiwa_link_7"
TIMESTEP_S = 0.001
GOAL = np.array([0.45, 0.25, 0.75])  # m, world frame: in front of the arm, to its left
REACH = np.array([0.5, 0.6, 0.0, -1.0, 0.0, 0.8, 0.0])  # rad, a pose near the goal
KP = np.array([2000.0, 2000.0, 1000.0, 1000.0, 100.0, 50.0, 10.0])  # N·m/rad
KD = np.array([100.0, 100.0, 50.0, 50.0, 5.0, 2.0, 0.3])  # N·m·s/rad


@dataclass
class Choice:
    """The imagined scores, the plan chosen, and where the flange ended live."""

    scores: np.ndarray  # m, one per plan
    best: int
    imagined: float  # m, the best plan's score
    live: float  # m, the flange's distance to the goal after executing it


def candidate_plans(joints: list[str], count: int, horizon: float,
                    seed: int = 7) -> list[list[dict[str, object]]]:
    """``count`` plans: a waypoint now, the final pose at half the horizon."""
    rng = np.random.default_rng(seed)

    def targets(pose: np.ndarray) -> dict[str, object]:
        return {"names": joints, "mode": "position", "targets": pose, "kp": KP, "kd": KD}
    plans = []
    for _ in range(count):
        final = REACH + rng.normal(0.0, 0.35, len(REACH))
        waypoint = final / 2
        plans.append([{"at": 0.0, "joint_targets": targets(waypoint)},
                      {"at": horizon / 2, "joint_targets": targets(final)}])
    return plans


def execute(sim: Client, plan: list[dict[str, object]], horizon: float) -> None:
    """The plan live: each target at its step, the steps in between."""
    done = 0
    ends = [*(round(float(str(item["at"])) / TIMESTEP_S) for item in plan[1:]),
            round(horizon / TIMESTEP_S)]
    for item, end in zip(plan, ends, strict=True):
        sim.set_joint_targets(**item["joint_targets"])  # type: ignore[arg-type]
        sim.step(end - done)
        done = end


def choose(sim: Client, count: int, horizon: float) -> Choice:
    sim.reset("all")
    sim.set_params({"timestep": TIMESTEP_S})
    sim.load_model("urdf", text=KUKA.read_text(), search_path=[KUKA.parent], fixed_base=True)
    joints = [joint.name for joint in sim.joints() if joint.type == "revolute"]
    plans = candidate_plans(joints, count, horizon)
    found = sim.predict(horizon, every=horizon, read=[FLANGE], plans=plans,
                        score={"body": FLANGE, "target": GOAL})
    assert found.scores is not None
    best = int(np.argmin(found.scores))
    execute(sim, plans[best], horizon)
    live = float(np.linalg.norm(sim.get_states([FLANGE]).poses[0, :3] - GOAL))
    print(f"{sim.status().engine}: imagined {count} plans in one call, scores (m) "
          f"{np.round(found.scores, 4)}; chose plan {best}: imagined {found.scores[best]:.6f}"
          f" m from the goal, live {live:.6f} m")
    return Choice(found.scores, best, float(found.scores[best]), live)


def main(argv: list[str]) -> Choice:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco", choices=("mujoco", "pybullet"))
    parser.add_argument("--plans", type=int, default=6)
    parser.add_argument("--horizon", type=float, default=0.6, help="sim seconds")
    parser.add_argument("--connect", help="a running daemon's endpoint")
    parser.add_argument("--instance", default="galton")
    args = parser.parse_args(argv)
    if args.connect:
        with Client(args.instance, args.connect, timeout=60.0) as sim:
            return choose(sim, args.plans, args.horizon)
    with EmbeddedDaemon(args.engine) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        return choose(sim, args.plans, args.horizon)


if __name__ == "__main__":
    main(sys.argv[1:])
