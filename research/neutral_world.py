"""A fresh world's own defaults on every engine: a dropped box, a bouncing ball, a stack.

Usage: python research/neutral_world.py [--engines mujoco,pybullet,ode,dart]
                                        [--board paper]

Starts one daemon per engine (as the tests do) and prints, per engine, what
tests/test_neutral_world.py holds to bar `neutral-world` (issue 48): a 20 cm, 1 kg box
dropped from 0.3 m onto the plane (its speed and spin 1 s after landing, its creep over the
second after, drift and tilt), a 5 cm ball's rebound from 1 m, and the top box of a stack of
three after 10 s. With ``--board``, the world is loaded with that board's settings and the
bodies carry its ball (moving) and floor (plane) surfaces: how the board's materials would
treat the same scene. Sim time runs flat out; the figures are deterministic.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from galton.analysis.board import BoardSpec
from galton.client import Client, EmbeddedDaemon, boxes, plane, spheres

HALF, DROP, BALL, BALL_DROP = 0.10, 0.3, 0.025, 1.0
LANDING = float(np.sqrt(2 * DROP / 9.8))


def surfaces(board: str | None, engine: str) -> tuple[dict[str, Any], dict[str, Any],
                                                      dict[str, Any]]:
    """The world's parameters, the moving bodies' and the plane's surfaces (none: defaults)."""
    if board is None:
        return {}, {}, {}
    contacts = BoardSpec.load(board).contacts[engine]
    ball, floor = contacts.bodies["ball"], contacts.bodies["floor"]
    return (dict(contacts.params), {"friction": ball.friction, "restitution": ball.restitution},
            {"friction": floor.friction, "restitution": floor.restitution})


def fresh(sim: Client, engine: str, params: dict[str, Any]) -> None:
    sim.load_world(engine, params or None)


def tilt(quaternion: np.ndarray) -> float:
    return float(np.arccos(np.clip(1 - 2 * (quaternion[0]**2 + quaternion[1]**2), -1, 1)))


def box_drop(sim: Client, engine: str, board: str | None) -> dict[str, float]:
    params, moving, ground = surfaces(board, engine)
    fresh(sim, engine, params)
    sim.spawn(plane(**ground), boxes(["box"], [[0, 0, HALF + DROP]], [HALF] * 3, mass=1.0,
                                     **moving))
    rested = sim.run_until_and_read(LANDING + 1.0, ["box"])
    later = sim.run_until_and_read(LANDING + 2.0, ["box"])
    return {"speed_mm_s": 1e3 * float(rested.speeds[0]),
            "spin_rad_s": float(np.linalg.norm(rested.twists[0, 3:])),
            "creep_mm": 1e3 * float(np.linalg.norm(later.positions[0] - rested.positions[0])),
            "drift_mm": 1e3 * float(np.linalg.norm(later.positions[0, :2])),
            "tilt_rad": tilt(later.poses[0, 3:])}


def ball_rebound(sim: Client, engine: str, board: str | None) -> float:
    params, moving, ground = surfaces(board, engine)
    fresh(sim, engine, params)
    sim.spawn(plane(**ground), spheres(["ball"], [[0, 0, BALL + BALL_DROP]], BALL, **moving))
    dt = sim.status().timestep
    chunk = max(1, round(0.005 / dt))
    landed, apex = False, 0.0
    for _ in range(round(1.5 / (chunk * dt))):
        height = sim.step_and_read(chunk, ["ball"]).positions[0, 2] - BALL
        landed = landed or height < 0.01
        apex = max(apex, height) if landed else apex
    return apex


def stack(sim: Client, engine: str, board: str | None) -> dict[str, float]:
    params, moving, ground = surfaces(board, engine)
    fresh(sim, engine, params)
    names = ["b0", "b1", "b2"]
    heights = [HALF, 3 * HALF, 5 * HALF]
    sim.spawn(plane(**ground), boxes(names, [[0, 0, z] for z in heights], [HALF] * 3,
                                     mass=1.0, **moving))
    end = sim.run_until_and_read(10.0, names)
    return {"top_drift_mm": 1e3 * float(np.linalg.norm(end.positions[2, :2])),
            "top_sink_mm": 1e3 * float(heights[2] - end.positions[2, 2])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="mujoco,pybullet,ode,dart")
    parser.add_argument("--board", default=None)
    args = parser.parse_args()
    for engine in args.engines.split(","):
        daemon = EmbeddedDaemon(engine, instance=f"neutral-{engine}").start()
        try:
            with Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
                print(json.dumps({"engine": engine, "board": args.board,
                                  "box": box_drop(sim, engine, args.board),
                                  "ball_rebound_m": ball_rebound(sim, engine, args.board),
                                  "stack": stack(sim, engine, args.board)}))
        finally:
            daemon.stop()


if __name__ == "__main__":
    main()
