"""Laws of motion without contact: free fall, a projectile, and a pendulum's period and
energy (the pendulum is a URDF hinge, so it needs an engine that loads URDF)."""

from __future__ import annotations

import math

import numpy as np

from galton.analysis import laws_theory as theory
from galton.analysis.laws import Check
from galton.client.laws.context import LawContext, joint_trace, unsupported
from galton.client.sdk.client import Client, spheres

INTEGRATOR = ("a first-order integrator (semi-implicit Euler) leads or lags the exact fall "
              "by g·t·dt/2; twice that")
FALL_SECONDS = 1.0
LAUNCH = (3.0, 0.0, 4.0)  # m/s, a projectile's initial velocity
FLIGHT_SECONDS = 0.8


def free_fall(sim: Client, ctx: LawContext) -> list[Check]:
    """A ball dropped from rest (no ground) falls g t²/2."""
    sim.spawn(spheres(["ball"], [[0, 0, 10.0]], 0.05))
    states = sim.step_and_read(ctx.steps(FALL_SECONDS), ["ball"])
    t = states.sim_time
    drop = 10.0 - float(states.positions[0, 2])
    return [Check("free-fall", f"drop after {t:g} s", "m", theory.fall_distance(ctx.gravity, t),
                  drop, ctx.gravity * t * ctx.timestep, INTEGRATOR)]


def projectile(sim: Client, ctx: LawContext) -> list[Check]:
    """A ball launched at (3, 0, 4) m/s: x = vx t exactly, z = vz t − g t²/2."""
    sim.spawn(spheres(["ball"], [[0, 0, 10.0]], 0.05, twists=[[*LAUNCH, 0, 0, 0]]))
    states = sim.step_and_read(ctx.steps(FLIGHT_SECONDS), ["ball"])
    t = states.sim_time
    x, _, z = states.positions[0]
    return [
        Check("projectile", f"distance after {t:g} s", "m", LAUNCH[0] * t, float(x), 1e-6,
              "no force acts along x: only rounding (and any damping the engine adds)"),
        Check("projectile", f"height gained after {t:g} s", "m",
              theory.projectile_height(LAUNCH[2], ctx.gravity, t), float(z) - 10.0,
              ctx.gravity * t * ctx.timestep, INTEGRATOR),
    ]


# -- a physical pendulum: a 1 kg bob 0.5 m below a hinge about y -------------------------
BOB_MASS = 1.0
ARM = 0.5
BOB_INERTIA = 0.01  # kg·m² about the bob's centre
PIVOT_INERTIA = BOB_INERTIA + BOB_MASS * ARM**2
SMALL_AMPLITUDE = 0.05  # rad
LARGE_AMPLITUDE = math.pi / 2  # rad: the exact period is 18 % longer than 2π√(I/mgd)
DRIFT_SECONDS = 60.0
SAMPLE_EVERY = 0.02  # s between joint reads
PERIOD_TOLERANCE = 0.005  # relative
PERIOD_WHY = ("the period from zero crossings interpolated between 20 ms samples; the "
              "integrator's own period error, (ω·dt)²/24, is below 1e-5")
DRIFT_TOLERANCE = 0.01  # relative
DRIFT_WHY = ("no damping and no contact: energy should stay; a symplectic step keeps it "
             "within an O(ω·dt) ripple without drift, so 1 % over 60 s")
HINGE = "hinge"


def pendulum_urdf() -> str:
    """A bob hanging ``ARM`` below a frictionless hinge 2 m up, fixed to the world."""
    i = BOB_INERTIA
    return f"""<robot name="pendulum">
  <link name="base"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="bob"><inertial><origin xyz="0 0 {-ARM}"/><mass value="{BOB_MASS}"/>
    <inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 {-ARM}"/><geometry><sphere radius="0.02"/></geometry>
    </collision></link>
  <joint name="{HINGE}" type="continuous"><parent link="base"/><child link="bob"/>
    <origin xyz="0 0 2"/><axis xyz="0 1 0"/><dynamics damping="0" friction="0"/></joint>
</robot>"""


def _exact_period(ctx: LawContext, amplitude: float) -> float:
    return theory.pendulum_period(PIVOT_INERTIA, BOB_MASS, ctx.gravity, ARM, amplitude)


def zero_crossings(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Where ``values`` changes sign, by linear interpolation."""
    i = np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]
    return np.asarray(times[i] - values[i] * (times[i + 1] - times[i])
                      / (values[i + 1] - values[i]), dtype=float)


def _period(times: np.ndarray, angles: np.ndarray) -> float:
    """The mean period over every whole period between the first and last crossing."""
    crossings = zero_crossings(times, angles)
    if len(crossings) < 3:
        return math.nan
    whole = (len(crossings) - 1) // 2 * 2
    return float((crossings[whole] - crossings[0]) / (whole / 2))


def _released(sim: Client, ctx: LawContext, amplitude: float) -> bool:
    if "urdf" not in ctx.capabilities.model_formats:
        return False
    sim.load_model("urdf", text=pendulum_urdf(), fixed_base=True)
    sim.set_joint_states([HINGE], [amplitude], [0.0])
    return True


def pendulum_small(sim: Client, ctx: LawContext) -> list[Check]:
    """The period at 0.05 rad against 4√(I/mgd) K(sin θ₀/2) (≈ 2π√(I/mgd))."""
    want = _exact_period(ctx, SMALL_AMPLITUDE)
    quantity = f"period at {SMALL_AMPLITUDE:g} rad"
    if not _released(sim, ctx, SMALL_AMPLITUDE):
        return unsupported("pendulum-small", [(quantity, "s", want, want * PERIOD_TOLERANCE,
                                               PERIOD_WHY)], "the engine loads no URDF")
    times, angles, _ = joint_trace(sim, ctx, HINGE, 3.2 * want, SAMPLE_EVERY)
    return [Check("pendulum-small", quantity, "s", want, _period(times, angles),
                  want * PERIOD_TOLERANCE, PERIOD_WHY)]


def pendulum_large(sim: Client, ctx: LawContext) -> tuple[list[Check], dict[str, np.ndarray]]:
    """The period at π/2 against the elliptic-integral period, and the energy's drift over
    60 s undamped (the mean of the last 5 s against the first 5 s)."""
    want = _exact_period(ctx, LARGE_AMPLITUDE)
    period_q = f"period at {LARGE_AMPLITUDE:.4g} rad"
    drift_q = f"energy drift over {DRIFT_SECONDS:g} s (relative)"
    if not _released(sim, ctx, LARGE_AMPLITUDE):
        return unsupported("pendulum-large", [
            (period_q, "s", want, want * PERIOD_TOLERANCE, PERIOD_WHY),
            (drift_q, "1", 0.0, DRIFT_TOLERANCE, DRIFT_WHY)], "the engine loads no URDF"), {}
    times, angles, rates = joint_trace(sim, ctx, HINGE, DRIFT_SECONDS, SAMPLE_EVERY)
    energy = theory.pendulum_energy(PIVOT_INERTIA, BOB_MASS, ctx.gravity, ARM, angles, rates)
    start = BOB_MASS * ctx.gravity * ARM * (1 - math.cos(LARGE_AMPLITUDE))
    relative = energy / start
    window = times <= 5.0
    late = times >= times[-1] - 5.0
    drift = float(relative[late].mean() - relative[window].mean())
    first = times <= 10.0
    checks = [Check("pendulum-large", period_q, "s", want, _period(times[first], angles[first]),
                    want * PERIOD_TOLERANCE, PERIOD_WHY),
              Check("pendulum-large", drift_q, "1", 0.0, drift, DRIFT_TOLERANCE, DRIFT_WHY)]
    return checks, {"pendulum energy / initial": np.vstack([times, relative])[:, ::5]}
