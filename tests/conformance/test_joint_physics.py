"""Joint and wrench physics against theory, through a real daemon, on every engine.

Each check names its tolerance. The timestep is 2 ms on both engines, so a difference
between them is the engine's, not the step's.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from support.models import (
    KUKA_JOINTS,
    KUKA_KD,
    KUKA_KP,
    G,
    Pendulum,
    apply_wrench,
    free_box_urdf,
    get_joint_states,
    load,
    load_robot,
    set_joint_states,
    set_targets,
    step_joints,
)

from galton.client import Client, body_group

DT = 0.002
HINGE = ["hinge"]


@pytest.fixture
def world(sim: Client) -> Client:
    """The engine's world with a 2 ms step and standard gravity."""
    sim.set_params({"timestep": DT, "gravity": [0.0, 0.0, -G]})
    return sim


def load_pendulum(sim: Client, pendulum: Pendulum, fmt: str = "urdf") -> None:
    load(sim, fmt, text=pendulum.urdf() if fmt == "urdf" else pendulum.mjcf())


def trajectory(sim: Client, seconds: float, every: int = 5) -> tuple[np.ndarray, np.ndarray]:
    """Times and hinge positions, read every ``every`` steps for ``seconds``."""
    times, positions = [0.0], [float(get_joint_states(sim, HINGE).positions[0])]
    for i in range(1, round(seconds / (DT * every)) + 1):
        times.append(i * every * DT)
        positions.append(float(step_joints(sim, every, HINGE).positions[0]))
    return np.array(times), np.array(positions)


def zero_crossings(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Where ``values`` changes sign, by linear interpolation."""
    i = np.nonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)[0]
    crossings: np.ndarray = times[i] - values[i] * (times[i + 1] - times[i]) / (
        values[i + 1] - values[i])
    return crossings


# -- a free pendulum -------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["urdf", "mjcf"])
def test_small_angle_period_is_two_pi_root_i_over_mgd(world: Client, fmt: str) -> None:
    pendulum = Pendulum()
    load_pendulum(world, pendulum, fmt)
    set_joint_states(world, HINGE, 0.02, 0.0)  # amplitude error (1 + θ²/16): 2.5e-5
    times, positions = trajectory(world, 1.4 * pendulum.period)
    first, _, third = zero_crossings(times, positions)[:3]
    assert third - first == pytest.approx(pendulum.period, rel=0.01)


# -- wrenches on free bodies -----------------------------------------------------------
def test_a_force_on_a_free_body_gives_f_over_m(world: Client) -> None:
    mass, force, steps = 2.0, np.array([3.0, -1.0, 0.0]), 100
    world.spawn(body_group("sphere", (0.1,), ["ball"], [[0, 0, 5]], mass=mass))
    load(world, "urdf", text=free_box_urdf(mass), prefix="f/", fixed_base=False)
    bodies = ["ball", "f/crate"]
    apply_wrench(world, bodies, np.tile(np.r_[force, 0, 0, 0], (2, 1)))
    world.step(steps)
    velocity = world.get_states(bodies).twists[:, :3]
    expected = force / mass * steps * DT
    for v in velocity:
        np.testing.assert_allclose(v[:2], expected[:2], rtol=0.01)
        assert v[2] == pytest.approx(-G * steps * DT, rel=0.01)  # gravity as before


def test_a_force_off_the_centre_turns_the_body(world: Client) -> None:
    mass, radius, force, steps = 2.0, 0.1, 4.0, 100
    world.spawn(body_group("sphere", (radius,), ["ball"], [[0, 0, 5]], mass=mass))
    apply_wrench(world, ["ball"], [[force, 0, 0, 0, 0, 0]], points=[[0, 0, 5 + radius]])
    world.step(steps)
    twist = world.get_states(["ball"]).twists[0]
    inertia = 0.4 * mass * radius**2  # a solid sphere
    assert twist[0] == pytest.approx(force / mass * steps * DT, rel=0.01)
    # (p - c) x F = (0, 0, r) x (F, 0, 0) = (0, r F, 0)
    assert twist[4] == pytest.approx(radius * force / inertia * steps * DT, rel=0.01)


# -- position targets ------------------------------------------------------------------
def held_angle(pendulum: Pendulum, target: float, kp: float) -> float:
    """Where a position target's pull kp (target - q) balances gravity's m g d sin q."""
    return float(brentq(lambda q: kp * (target - q) - pendulum.gravity_torque * math.sin(q),
                        0.0, target))


POSITION_TOLERANCE = 1e-3  # rad, from the angle where the target's pull balances gravity


def test_a_position_target_is_reached_and_held(world: Client) -> None:
    pendulum, target, kp, kd = Pendulum(), 0.6, 1000.0, 30.0
    load_pendulum(world, pendulum)
    set_targets(world, HINGE, "position", target, kp=kp, kd=kd)
    _, settled = trajectory(world, 1.0)
    _, held = trajectory(world, 0.5)
    expected = held_angle(pendulum, target, kp)
    assert abs(settled[-1] - expected) < POSITION_TOLERANCE
    assert np.abs(held - expected).max() < POSITION_TOLERANCE  # held, not passing through
    state = get_joint_states(world, HINGE)
    assert abs(state.velocities[0]) < 1e-3
    assert state.efforts[0] == pytest.approx(kp * (target - state.positions[0])
                                             - kd * state.velocities[0], rel=1e-6)


def test_a_horizontal_link_needs_effort_mgd(world: Client) -> None:
    pendulum, kp, kd = Pendulum(), 2000.0, 40.0
    load_pendulum(world, pendulum)
    set_joint_states(world, HINGE, math.pi / 2)
    set_targets(world, HINGE, "position", math.pi / 2, kp=kp, kd=kd)
    state = step_joints(world, round(1.5 / DT), HINGE)
    assert abs(state.velocities[0]) < 1e-3
    assert state.efforts[0] == pytest.approx(pendulum.gravity_torque, rel=0.01)


def test_a_velocity_target_turns_the_joint_at_that_speed(world: Client) -> None:
    world.set_params({"gravity": [0.0, 0.0, 0.0]})
    load_pendulum(world, Pendulum())
    set_targets(world, HINGE, "velocity", 2.0, kd=20.0)
    state = step_joints(world, round(0.5 / DT), HINGE)
    assert state.velocities[0] == pytest.approx(2.0, rel=1e-3)


def test_an_effort_is_clipped_to_max_effort(world: Client) -> None:
    pendulum = Pendulum()
    load_pendulum(world, pendulum)
    set_targets(world, HINGE, "effort", 50.0, max_effort=3.0)
    state = step_joints(world, 1, HINGE)
    assert state.efforts[0] == 3.0
    # from rest at the bottom, gravity's torque is nil: α = τ / I
    assert state.velocities[0] == pytest.approx(3.0 / pendulum.pivot_inertia * DT, rel=0.01)


# -- limits ----------------------------------------------------------------------------
LIMIT_TOLERANCE = 0.005  # rad past the limit, held against 4 × the torque gravity gives
LIMIT_TRANSIENT = 0.02  # rad past it while the push first loads the limit


@pytest.mark.parametrize("side", [1, -1], ids=["upper", "lower"])
def test_a_joint_limit_holds_against_an_effort(world: Client, side: int) -> None:
    """Started at rest on the limit: an impact would measure the engine's constraint
    softness, not the limit (MuJoCo's soft limit lets an 8 rad/s arrival pass by 0.05 rad
    before pushing it back)."""
    pendulum = Pendulum(lower=-0.5, upper=0.5)
    load_pendulum(world, pendulum)
    set_joint_states(world, HINGE, side * 0.5, 0.0)
    set_targets(world, HINGE, "effort", side * 4 * pendulum.gravity_torque)
    _, positions = trajectory(world, 1.0)
    past = side * positions - 0.5
    assert past.max() < LIMIT_TRANSIENT
    assert np.abs(past[len(past) // 2:]).max() < LIMIT_TOLERANCE  # held on the limit


# -- a robot arm tracking a trajectory -------------------------------------------------
# With KUKA_KP and KUKA_KD, measured on both engines: worst joint 0.037 rad (joint 7: the
# lag kd/kp · q̇ with no velocity feed-forward), rms 0.017 rad.
TRACKING_TOLERANCE = 0.05  # rad, worst joint, after the first half second


def kuka_reference(t: float) -> np.ndarray:
    """0.4 rad at 0.5 Hz on every joint, phases spread, from the straight-up pose."""
    phases = np.arange(7) * 0.5
    reference: np.ndarray = 0.4 * (np.sin(2 * np.pi * 0.5 * t + phases) - np.sin(phases))
    return reference


def track_kuka(sim: Client, seconds: float, rate: float = 100.0) -> np.ndarray:
    """Stream position targets at ``rate`` Hz; the tracking error at each cycle."""
    every = round(1 / (rate * DT))
    errors = []
    for cycle in range(round(seconds * rate)):
        t = cycle * every * DT
        set_targets(sim, KUKA_JOINTS, "position", kuka_reference(t + every * DT),
                    kp=KUKA_KP, kd=KUKA_KD)
        read = step_joints(sim, every, KUKA_JOINTS)
        errors.append(read.positions - kuka_reference(t + every * DT))
    return np.array(errors)


def test_kuka_tracks_a_sinusoid_with_position_targets(world: Client) -> None:
    load_robot(world, "kuka")
    errors = np.abs(track_kuka(world, 2.0))
    settled = errors[50:]
    print(f"kuka tracking error after 0.5 s: max {settled.max():.4f} rad, "
          f"rms {np.sqrt((settled**2).mean()):.4f} rad")
    assert settled.max() < TRACKING_TOLERANCE


def test_kuka_holds_a_pose_at_the_gains_robot_users_type(sim: Client) -> None:
    """kp 400 N·m/rad, kd 40 N·m·s on all seven joints, at the engine's default settings
    (issue 33: link 7's 6e-4 kg·m² made an explicit kd shake the arm at its velocity
    limit). After 3 s each joint is within its static sag kp^-1·τ_gravity + 1e-3 rad of the
    target, at rest (1e-3 rad/s), its effort the law's."""
    load_robot(sim, "kuka")
    target = np.array([0.3, 0.5, -0.2, -1.0, 0.4, 0.6, 0.2])
    set_targets(sim, KUKA_JOINTS, "position", target, kp=400.0, kd=40.0)
    steps = round(3.0 / sim.get_params()["timestep"])
    held = step_joints(sim, steps, KUKA_JOINTS)
    sag = np.abs(held.efforts) / 400.0
    assert np.all(np.abs(held.positions - target) <= sag + 1e-3), held.positions - target
    assert np.abs(held.velocities).max() < 1e-3
    np.testing.assert_allclose(held.efforts, 400.0 * (target - held.positions)
                               - 40.0 * held.velocities, atol=1e-3)
    assert np.abs(held.efforts).max() < 100.0  # gravity's torques, not a saturated chatter
