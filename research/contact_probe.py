"""An engine's default contact in physical terms, measured in-process on the daemon's engine.

Usage: python research/contact_probe.py [--engine mujoco] [--params JSON] [--apex-drops N]
       python research/contact_probe.py --impact-speeds 0.45,0.95,1.9,3.0 [--params JSON]

Prints one JSON line:
- ``drop_bounce``: e = v_out / v_in at the first impact of a ball (r 0.045 m, 0.38 kg)
  dropped 0.5, 1 and 2 m onto a static box;
- ``head_on_bounce``: separating over approaching speed of two such balls meeting head-on
  in zero gravity at 0.5, 1 and 3 m/s;
- ``slide_friction``: deceleration / g of a 1 kg box launched at 1 and 3 m/s on the floor;
- ``asleep_after_s``: when a ball dropped 0.3 to 2 m onto a plane stops for good (its
  speed reads exactly 0; ``null``: still moving after 5 s);
- ``apex_kept``: of N balls dropped onto the top of a pin (offsets within ±2 mm, heights
  0.02 to 0.5 m, seeded), how many are still on the pin after 4 s;
- ``never_asleep``: of balls dropped from 0.05 to 0.99 m in 1 cm steps onto a box floor,
  how many still move after 8 s (a hop that never ends), and from which heights.

docs/physics/mujoco.md quotes these figures for the defaults. ``--impact-speeds`` prints only
the drop bounce, at these impact speeds (m/s): how e depends on speed, and the most a setting
can give (docs/research/physics-notebook.md, "Could an engine bounce like that?").
"""

from __future__ import annotations

import argparse
import json
import math
from typing import Any

import numpy as np

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup

RADIUS, MASS, GRAVITY = 0.045, 0.38, 9.81
IDENTITY = (0.0, 0.0, 0.0, 1.0)
ALONG_Y = (math.sqrt(0.5), 0.0, 0.0, math.sqrt(0.5))  # a cylinder's axis turned to y


def body(shape: str, name: str, position: tuple[float, ...], size: tuple[float, ...],
         static: bool = False, twist: tuple[float, ...] | None = None,
         quat: tuple[float, ...] = IDENTITY, mass: float | None = None) -> BodyGroup:
    return BodyGroup(shape=shape, size=size, names=[name],
                     poses=np.array([[*position, *quat]], dtype=float), static=static,
                     twists=None if twist is None else np.array([twist], dtype=float),
                     mass=mass)


def fresh(name: str, params: dict[str, Any], *groups: BodyGroup) -> Engine:
    engine = create_engine(name)
    engine.set_params(params)
    engine.spawn(list(groups))
    return engine


def run(engine: Engine, seconds: float) -> None:
    engine.step(round(seconds / engine.timestep))


def drop_bounce(name: str, params: dict[str, Any], height: float) -> float:
    floor = body("box", "floor", (0, 0, -0.05), (2, 2, 0.05), static=True)
    ball = body("sphere", "ball", (0, 0, RADIUS + height), (RADIUS,), mass=MASS)
    engine = fresh(name, params, floor, ball)
    speeds = []
    for _ in range(round((math.sqrt(2 * height / GRAVITY) + 0.3) / engine.timestep)):
        engine.step(1)
        speeds.append(engine.get_states(["ball"])[1][0, 2])
    impact = int(np.argmax(np.array(speeds) > 0))
    return max(speeds[impact:]) / -min(speeds[:impact])


def head_on_bounce(name: str, params: dict[str, Any], speed: float) -> float:
    engine = fresh(name, {**params, "gravity": [0.0, 0.0, 0.0]},
                   body("sphere", "a", (-0.2, 0, 1), (RADIUS,), twist=(speed, 0, 0, 0, 0, 0),
                        mass=MASS),
                   body("sphere", "b", (0.2, 0, 1), (RADIUS,), twist=(-speed, 0, 0, 0, 0, 0),
                        mass=MASS))
    run(engine, 0.5)
    velocity = engine.get_states(["a", "b"])[1][:, 0]
    return float((velocity[1] - velocity[0]) / (2 * speed))


def slide_friction(name: str, params: dict[str, Any], speed: float) -> float:
    engine = fresh(name, params, body("box", "floor", (0, 0, -0.05), (20, 20, 0.05), static=True),
                   body("box", "crate", (0, 0, 0.05), (0.05, 0.05, 0.05), mass=1.0))
    run(engine, 0.3)
    engine.set_states(["crate"], None, np.array([[speed, 0, 0, 0, 0, 0]]))
    run(engine, 0.1)
    return float((speed - engine.get_states(["crate"])[1][0, 0]) / 0.1 / GRAVITY)


def asleep_after(name: str, params: dict[str, Any], height: float) -> float | None:
    engine = fresh(name, params, body("plane", "ground", (0, 0, 0), (5, 5), static=True),
                   body("sphere", "ball", (0, 0, RADIUS + height), (RADIUS,), mass=MASS))
    for tick in range(1, 26):
        run(engine, 0.2)
        if not engine.get_states(["ball"])[1].any():
            return round(tick * 0.2, 1)
    return None


def apex_kept(name: str, params: dict[str, Any], drops: int) -> int:
    rng = np.random.default_rng(1)
    kept = 0
    for _ in range(drops):
        offset, height = rng.uniform(-2e-3, 2e-3), rng.uniform(0.02, 0.5)
        engine = fresh(name, params,
                       body("cylinder", "pin", (0, 0, 1.0), (0.1, 0.275), static=True,
                            quat=ALONG_Y),
                       body("plane", "ground", (0, 0, 0), (5, 5), static=True),
                       body("sphere", "ball", (offset, 0, 1.0 + 0.1 + RADIUS + height),
                            (RADIUS,), mass=MASS))
        run(engine, 4.0)
        kept += int(engine.get_states(["ball"])[0][0, 2] > 1.0)
    return kept


def never_asleep(name: str, params: dict[str, Any]) -> list[float]:
    heights = []
    for height in np.round(np.arange(0.05, 1.0, 0.01), 2):
        engine = fresh(name, params,
                       body("box", "floor", (0, 0, -0.05), (5, 5, 0.05), static=True),
                       body("sphere", "ball", (0, 0, RADIUS + height), (RADIUS,), mass=MASS))
        run(engine, 8.0)
        if engine.get_states(["ball"])[1].any():
            heights.append(float(height))
    return heights


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--params", default="{}", help="engine parameters as JSON")
    parser.add_argument("--apex-drops", type=int, default=150)
    parser.add_argument("--impact-speeds", help="comma-separated m/s: the drop bounce only")
    args = parser.parse_args()
    name, params = args.engine, json.loads(args.params)
    if args.impact_speeds:
        speeds = [float(v) for v in args.impact_speeds.split(",")]
        print(json.dumps({"engine": name, "params": params, "drop_bounce_at_speed": {
            v: round(drop_bounce(name, params, v * v / (2 * GRAVITY)), 3) for v in speeds}}))
        return
    hops = never_asleep(name, params)
    print(json.dumps({
        "engine": name, "params": params,
        "drop_bounce": {h: round(drop_bounce(name, params, h), 3) for h in (0.5, 1.0, 2.0)},
        "head_on_bounce": {v: round(head_on_bounce(name, params, v), 3)
                           for v in (0.5, 1.0, 3.0)},
        "slide_friction": {v: round(slide_friction(name, params, v), 3) for v in (1.0, 3.0)},
        "asleep_after_s": {h: asleep_after(name, params, h)
                           for h in (0.3, 0.5, 0.7, 1.0, 1.5, 2.0)},
        "apex_kept": f"{apex_kept(name, params, args.apex_drops)} of {args.apex_drops}",
        "never_asleep": f"{len(hops)} of 95: {hops}",
    }))


if __name__ == "__main__":
    main()
