"""What setting every ball's restitution between steps would cost PyBullet.

Usage: python research/per_ball_bounce_cost.py [--balls 500] [--repeats 50]

Why: a bounce that falls with speed (docs/research/physics-notebook.md, "Could an engine
bounce like that?") could be emulated by giving each ball, between steps, the restitution
its speed asks for.
PyBullet takes it one body at a time (``changeDynamics``), so this times that loop over
BALLS balls, beside one step of the same balls falling free (no contacts: a floor for the
step's own cost, which a crowd raises). Prints one JSON line, milliseconds per step.
"""

from __future__ import annotations

import argparse
import json
import time

import pybullet

RADIUS, MASS = 0.045, 0.38


def per_step_ms(action, repeats: int) -> float:
    """Mean wall time of one call of ``action``, in ms."""
    start = time.perf_counter()
    for index in range(repeats):
        action(index)
    return (time.perf_counter() - start) / repeats * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, default=500)
    parser.add_argument("--repeats", type=int, default=50)
    args = parser.parse_args()
    client = pybullet.connect(pybullet.DIRECT)
    shape = pybullet.createCollisionShape(pybullet.GEOM_SPHERE, radius=RADIUS,
                                          physicsClientId=client)
    balls = [pybullet.createMultiBody(MASS, shape, basePosition=[0.1 * i, 0.0, 10.0],
                                      physicsClientId=client) for i in range(args.balls)]

    def set_restitutions(index: int) -> None:
        for ball in balls:
            pybullet.changeDynamics(ball, -1, restitution=0.5 + 1e-4 * index,
                                    physicsClientId=client)

    set_ms = per_step_ms(set_restitutions, args.repeats)
    step_ms = per_step_ms(lambda _: pybullet.stepSimulation(physicsClientId=client),
                          args.repeats)
    pybullet.disconnect(client)
    print(json.dumps({"balls": args.balls, "set_restitution_ms": round(set_ms, 3),
                      "free_step_ms": round(step_ms, 3)}))


if __name__ == "__main__":
    main()
