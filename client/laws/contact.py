"""Laws of contact with a static surface: rolling and sliding down an incline, a puck
sliding to rest, a ball's rebound.

The coefficient asked for sits on the static surface, the moving body's is 1 (friction)
or 1 (restitution): 1 is the neutral value of the product rule (PyBullet, DART's
restitution), and under the rules that let the static surface win (MuJoCo's priority) or
take the smaller value (DART's friction) the static one is the contact's. So every engine
is asked for the same contact without the suite knowing its rule.
"""

from __future__ import annotations

import math

import numpy as np

from galton.analysis import laws_theory as theory
from galton.analysis.laws import Check
from galton.client.laws.context import LawContext, trace
from galton.client.sdk.client import Client, body_group, plane
from galton.protocol import BodyGroup

SLOPE_FRICTION = 0.5  # the incline's μ: a friction angle of 26.6°
ROLL_SLOPE = math.radians(20.0)
HOLD_SLOPE = math.radians(20.0)
SLIDE_SLOPE = math.radians(35.0)
RUN_SECONDS = 1.0
FIT_FROM = 0.1  # s: the acceleration is fitted after the first contact has settled
ROLL_TOLERANCE = 0.02  # relative
ROLL_WHY = ("a soft contact lets the body sink a little into the slope (a rolling "
            "resistance) and the contact point is found once per step: 2 %")
SLIDE_TOLERANCE = 0.03  # relative
SLIDE_WHY = ("Coulomb friction is solved approximately (a friction cone or pyramid, an "
             "iterative or soft solver): 3 %")
HOLD_TOLERANCE = 0.001  # m
HOLD_WHY = "a held block may creep where friction is soft (a regularised cone): 1 mm in 2 s"


def _incline(slope: float) -> tuple[BodyGroup, np.ndarray, np.ndarray, np.ndarray]:
    """A static 4 m slab turned ``slope`` about y (so +x' runs downhill); its turn, its
    downhill direction and its top surface's normal."""
    turn = theory.quaternion_about((0, 1, 0), slope)
    pose = np.r_[0.0, 0.0, 0.0, turn]
    slab = BodyGroup("box", (2.0, 0.5, 0.05), ["incline"], pose.reshape(1, 7), static=True,
                     friction=SLOPE_FRICTION, restitution=0.0)
    downhill = np.array([math.cos(slope), 0.0, -math.sin(slope)])
    normal = np.array([math.sin(slope), 0.0, math.cos(slope)])
    return slab, turn, downhill, normal


def _on_incline(shape: str, size: tuple[float, ...], standoff: float, slope: float,
                own_turn: np.ndarray | None = None) -> tuple[BodyGroup, BodyGroup, np.ndarray]:
    """The incline and one body resting on it 1.5 m uphill of the centre, at rest."""
    slab, turn, downhill, normal = _incline(slope)
    centre = (0.05 + standoff) * normal - 1.5 * downhill
    quaternion = turn if own_turn is None else theory.quaternion_product(turn, own_turn)
    body = BodyGroup(shape, size, ["body"], np.r_[centre, quaternion].reshape(1, 7),
                     mass=1.0, friction=1.0, restitution=0.0)
    return slab, body, downhill


def _acceleration(sim: Client, ctx: LawContext, downhill: np.ndarray) -> tuple[float, float]:
    """The body's fitted acceleration along the slope, and how far it went, over 1 s."""
    run = trace(sim, ctx, ["body"], RUN_SECONDS, 0.05)
    along = (run.poses[:, 0, :3] - run.poses[0, 0, :3]) @ downhill
    late = run.times >= FIT_FROM
    curve = np.polyfit(run.times[late], along[late], 2)
    return float(2.0 * curve[0]), float(along[-1])


def _rolling(sim: Client, ctx: LawContext, law: str, shape: str, size: tuple[float, ...],
             ratio: float, own_turn: np.ndarray | None) -> list[Check]:
    slab, body, downhill = _on_incline(shape, size, size[0], ROLL_SLOPE, own_turn)
    sim.spawn(slab, body)
    got, _ = _acceleration(sim, ctx, downhill)
    want = theory.rolling_acceleration(ctx.gravity, ROLL_SLOPE, ratio)
    return [Check(law, "acceleration down a 20° slope", "m/s²", want, got,
                  want * ROLL_TOLERANCE, ROLL_WHY)]


def rolling_sphere(sim: Client, ctx: LawContext) -> list[Check]:
    """A solid sphere rolls without slipping down 20° (μ 0.5): 5/7 g sin θ."""
    return _rolling(sim, ctx, "rolling-sphere", "sphere", (0.1,), theory.SOLID_SPHERE, None)


def rolling_cylinder(sim: Client, ctx: LawContext) -> list[Check]:
    """A solid cylinder, its axis across the slope, rolls down 20°: 2/3 g sin θ."""
    across = theory.quaternion_about((1, 0, 0), math.pi / 2)  # its z axis along world y
    return _rolling(sim, ctx, "rolling-cylinder", "cylinder", (0.1, 0.1),
                    theory.SOLID_CYLINDER, across)


def block_incline(sim: Client, ctx: LawContext) -> list[Check]:
    """A block (μ 0.5) holds on 20° (under its friction angle, 26.6°) and slides down 35°
    at g (sin θ − μ cos θ)."""
    slab, block, downhill = _on_incline("box", (0.1, 0.1, 0.05), 0.05, HOLD_SLOPE)
    sim.spawn(slab, block)
    run = trace(sim, ctx, ["body"], 2.0, 1.0)
    crept = float(np.linalg.norm(run.poses[-1, 0, :3] - run.poses[0, 0, :3]))
    sim.delete(["incline", "body"])
    slab, block, downhill = _on_incline("box", (0.1, 0.1, 0.05), 0.05, SLIDE_SLOPE)
    sim.spawn(slab, block)
    got, _ = _acceleration(sim, ctx, downhill)
    want = theory.sliding_acceleration(ctx.gravity, SLIDE_SLOPE, SLOPE_FRICTION)
    return [Check("block-incline", "creep in 2 s on 20° (holds)", "m", 0.0, crept,
                  HOLD_TOLERANCE, HOLD_WHY),
            Check("block-incline", "acceleration down 35° (slides)", "m/s²", want, got,
                  want * SLIDE_TOLERANCE, SLIDE_WHY)]


PUCK_FRICTION = 0.3
PUCK_SPEED = 2.0  # m/s
PUCK_TOLERANCE = 0.03  # relative
PUCK_WHY = ("Coulomb friction solved approximately, and the stop is found to a step: 3 %")


def puck(sim: Client, ctx: LawContext) -> list[Check]:
    """A puck pushed at 2 m/s on level ground (μ 0.3) slides v²/(2 μ g) and stops."""
    puck_body = body_group("cylinder", (0.1, 0.02), ["puck"], [[0, 0, 0.02]], mass=1.0,
                           friction=1.0, restitution=0.0, twists=[[PUCK_SPEED, 0, 0, 0, 0, 0]])
    sim.spawn(plane(friction=PUCK_FRICTION, restitution=0.0), puck_body)
    want = theory.sliding_distance(PUCK_SPEED, PUCK_FRICTION, ctx.gravity)
    states, _ = sim.run_until_rest(3.0, ["puck"], speed=1e-3, every=0.05)
    return [Check("puck", "sliding distance from 2 m/s", "m", want,
                  float(states.positions[0, 0]), want * PUCK_TOLERANCE, PUCK_WHY)]


DROP = 1.0  # m from the ball's lowest point to the plane
ASKED_RESTITUTION = 0.5
RADIUS = 0.05
REBOUND_WHY = ("e within ±0.05: a compliant contact's bounce depends on its stiffness, "
               "damping and the step, not only on the coefficient")


def rebound(sim: Client, ctx: LawContext) -> tuple[list[Check], dict[str, np.ndarray]]:
    """A ball dropped 1 m on a plane asked for e = 0.5 bounces back to e² h = 0.25 m."""
    sim.spawn(plane(restitution=ASKED_RESTITUTION, friction=0.5),
              body_group("sphere", (RADIUS,), ["ball"], [[0, 0, DROP + RADIUS]], mass=0.1,
                         restitution=1.0, friction=1.0))
    run = trace(sim, ctx, ["ball"], 0.9, 0.005)
    heights = run.poses[:, 0, 2] - RADIUS
    rising = np.nonzero(run.twists[:, 0, 2] > 0)[0]
    bounced = float(heights[rising[0]:].max()) if len(rising) else 0.0
    want = theory.rebound_height(DROP, ASKED_RESTITUTION)
    tolerance = 2 * ASKED_RESTITUTION * DROP * 0.05
    return ([Check("rebound", f"rebound height from {DROP:g} m, e {ASKED_RESTITUTION:g}", "m",
                   want, bounced, tolerance, REBOUND_WHY)],
            {"rebound height": np.vstack([run.times, heights])})
