"""Laws among moving bodies: a two-sphere collision, Newton's cradle, a tower of boxes,
and a torque-free asymmetric body (the intermediate-axis flip).

The collisions happen in free fall with no ground: gravity pulls every body alike, so the
relative motion is that of weightless bodies, and no engine parameter is needed. Both
bodies of a collision are asked for e = 1, the one value every rule of combining two
bodies' coefficients (product, mean, min, max) keeps.
"""

from __future__ import annotations

import numpy as np

from galton.analysis import laws_theory as theory
from galton.analysis.laws import Check
from galton.client.laws.context import LawContext, trace
from galton.client.sdk.client import Client, body_group, boxes, plane

MOMENTUM_TOLERANCE = 1e-3  # relative
MOMENTUM_WHY = ("contact forces act in equal and opposite pairs, so momentum is kept to "
                "rounding; 0.1 % allows a solver that spreads an impulse over a few steps")
ELASTIC_TOLERANCE = 0.05
ELASTIC_WHY = ("a compliant contact keeps some energy in its damping even when asked for "
               "e = 1: 0.05")


def two_spheres(sim: Client, ctx: LawContext) -> list[Check]:
    """A 1 kg sphere at 1 m/s meets a 2 kg one at rest head-on (e asked 1): momentum is
    kept, and they part at e times their closing speed."""
    m1, m2, v1 = 1.0, 2.0, 1.0
    sim.spawn(body_group("sphere", (0.1,), ["light"], [[0, 0, 50]], mass=m1, restitution=1.0,
                         friction=0.0, twists=[[v1, 0, 0, 0, 0, 0]]),
              body_group("sphere", (0.1,), ["heavy"], [[0.5, 0, 50]], mass=m2,
                         restitution=1.0, friction=0.0))
    states = sim.step_and_read(ctx.steps(0.8), ["light", "heavy"])
    after1, after2 = states.twists[:, 0]
    momentum = (m1 * after1 + m2 * after2) / (m1 * v1)
    restitution = (after2 - after1) / v1
    return [Check("two-spheres", "momentum after / before", "1", 1.0, float(momentum),
                  MOMENTUM_TOLERANCE, MOMENTUM_WHY),
            Check("two-spheres", "restitution (separation / approach speed)", "1", 1.0,
                  float(restitution), ELASTIC_TOLERANCE, ELASTIC_WHY)]


CRADLE_BALLS = 5
CRADLE_GAP = 0.001  # m between neighbours at rest
CRADLE_TOLERANCE = 0.1
CRADLE_WHY = ("with a 1 mm gap the impacts are sequential and ideal elastic ones pass all "
              "the momentum down the row; a solver that treats them at once, or damps each, "
              "spreads it: 10 % of the speed")


def cradle(sim: Client, ctx: LawContext) -> list[Check]:
    """Newton's cradle: five equal balls in a row 1 mm apart, the first hits at 1 m/s;
    the last leaves at 1 m/s and the others stay still."""
    radius, speed = 0.05, 1.0
    pitch = 2 * radius + CRADLE_GAP
    names = [f"ball{i}" for i in range(CRADLE_BALLS)]
    xs = [-0.2] + [i * pitch for i in range(1, CRADLE_BALLS)]  # the first 0.2 m off
    twists = np.zeros((CRADLE_BALLS, 6))
    twists[0, 0] = speed
    sim.spawn(body_group("sphere", (radius,), names, [[x, 0, 50] for x in xs], mass=0.1,
                         restitution=1.0, friction=0.0, twists=twists))
    states = sim.step_and_read(ctx.steps(0.5), names)
    vx = states.twists[:, 0] / speed
    return [Check("cradle", "last ball's speed / incoming", "1", 1.0, float(vx[-1]),
                  CRADLE_TOLERANCE, CRADLE_WHY),
            Check("cradle", "largest other ball's speed / incoming", "1", 0.0,
                  float(np.abs(vx[:-1]).max()), CRADLE_TOLERANCE, CRADLE_WHY)]


TOWER_BOXES = 10
TOWER_SECONDS = 10.0
TOWER_DRIFT_TOLERANCE = 0.005  # m
TOWER_DRIFT_WHY = ("a stack in equilibrium stands: its top should not move sideways; 5 mm "
                   "allows a solver's jitter, a toppling tower moves metres")
TOWER_SINK_TOLERANCE = 0.01  # m
TOWER_SINK_WHY = ("a soft contact holds a weight by sinking into it, up to about 1 mm per "
                  "contact in a well-tuned engine: 10 mm over the 10 contacts below the top")


def tower(sim: Client, ctx: LawContext) -> list[Check]:
    """Ten 10 cm boxes stacked exactly on a plane stand for 10 s: the top one neither
    drifts sideways nor sinks more than the contacts' give."""
    names = [f"box{i}" for i in range(TOWER_BOXES)]
    half = 0.05
    sim.spawn(plane(friction=0.5, restitution=0.0),
              boxes(names, [[0, 0, half + 2 * half * i] for i in range(TOWER_BOXES)],
                    (half, half, half), mass=0.5, friction=0.5, restitution=0.0))
    start = sim.get_states([names[-1]]).positions[0]
    moved = sim.step_and_read(ctx.steps(TOWER_SECONDS), [names[-1]]).positions[0] - start
    return [Check("tower", f"top box's sideways drift after {TOWER_SECONDS:g} s", "m", 0.0,
                  float(np.linalg.norm(moved[:2])), TOWER_DRIFT_TOLERANCE, TOWER_DRIFT_WHY),
            Check("tower", f"top box's sinking after {TOWER_SECONDS:g} s", "m", 0.0,
                  float(-moved[2]), TOWER_SINK_TOLERANCE, TOWER_SINK_WHY)]


SPINNER_HALF = (0.05, 0.1, 0.2)  # m: three distinct moments, the intermediate about y
SPIN = 4.0  # rad/s about the intermediate axis
SPIN_SECONDS = 8.0
ANGULAR_TOLERANCE = 0.01  # relative
ANGULAR_WHY = ("no torque acts, so L is constant; an explicit step of the rotation "
               "(dropping or linearising the gyroscopic term) drifts: 1 % over 8 s")
FLIP_TOLERANCE = 0.05
FLIP_WHY = ("a spin about the intermediate axis is unstable: a small wobble grows until "
            "the axis turns over (to -1 along L, within 0.05), and back")


def torque_free(sim: Client, ctx: LawContext) -> tuple[list[Check], dict[str, np.ndarray]]:
    """An asymmetric box spun about its intermediate axis with a small seeded wobble, in
    free fall: its angular momentum stays, and the axis flips over."""
    wobble = ctx.rng.uniform(0.01, 0.03, size=2) * SPIN
    spin = [0, 0, 0, wobble[0], SPIN, wobble[1]]
    sim.spawn(boxes(["spinner"], [[0, 0, 400]], SPINNER_HALF, mass=1.0, twists=[spin]))
    run = trace(sim, ctx, ["spinner"], SPIN_SECONDS, 0.02)
    principal = theory.box_inertia(1.0, SPINNER_HALF)
    momenta = theory.angular_momentum(principal, run.poses[:, 0, 3:], run.twists[:, 0, 3:])
    size = np.linalg.norm(momenta[0])
    drift = np.linalg.norm(momenta - momenta[0], axis=1) / size
    axis_along_l = theory.rotation_matrices(run.poses[:, 0, 3:])[:, :, 1] @ (momenta[0] / size)
    drift_q = f"largest drift of L (relative) over {SPIN_SECONDS:g} s"
    return ([Check("torque-free", drift_q, "1", 0.0, float(drift.max()), ANGULAR_TOLERANCE,
                   ANGULAR_WHY),
             Check("torque-free", "intermediate axis along L, at its lowest", "1", -1.0,
                   float(axis_along_l.min()), FLIP_TOLERANCE, FLIP_WHY)],
            {"torque-free drift of L (relative)": np.vstack([run.times, drift]),
             "torque-free intermediate axis · L": np.vstack([run.times, axis_along_l])})
