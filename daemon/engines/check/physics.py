"""Engine checks of the physics every engine must get right: time, free fall, contact,
static bodies, determinism, the rewind to the created state, and divergence."""

from __future__ import annotations

import math

import numpy as np

from galton.daemon.engines.base import FEATURE_DELETE, FEATURE_SET_STATE, Engine
from galton.daemon.engines.check.support import (
    TURNED,
    CheckContext,
    expect,
    expect_close,
    expect_identical,
    expect_poses,
    gravity,
    ground,
    group,
    poses_at,
    skip_unless,
    states,
)
from galton.protocol import BodyGroup

LIMITS = (1e6, 1e5)  # the daemon's default max_position (m) and max_speed (m/s)
REST_TOLERANCE = 0.005  # m a ball at rest may sink into, or float over, a plane
REST_SPEED = 0.01  # m/s and rad/s, the most a ball at rest may still move or turn


def check_timestep(ctx: CheckContext) -> None:
    """step(n) advances time by n timesteps: a body gliding at 1 m/s in no gravity moves
    n·dt metres (within 1e-9 m); a new "timestep" parameter is the new step's length."""
    engine = ctx.engine
    if "gravity" in engine.get_params():
        engine.set_params({"gravity": [0.0, 0.0, 0.0]})
    expect(not gravity(engine).any(), "gravity to glide in", "none", gravity(engine))
    engine.spawn([group("sphere", ["glider"], [0, 0, 1], twists=[1, 0, 0, 0, 0, 0])])
    dt = engine.timestep
    for steps in (1, 10, 100):
        start = engine.get_states(["glider"])[0][0, 0]
        engine.step(steps)
        moved = engine.get_states(["glider"])[0][0, 0] - start
        expect(abs(moved - steps * dt) <= 1e-9, f"the distance glided at 1 m/s in {steps} "
               f"steps of {dt:g} s", f"{steps * dt!r} m", f"{moved!r} m")
    if "timestep" not in engine.get_params():
        return
    engine.set_params({"timestep": dt / 2})
    expect(engine.timestep == dt / 2, "timestep after setting it", repr(dt / 2),
           engine.timestep)
    start = engine.get_states(["glider"])[0][0, 0]
    engine.step(10)
    moved = engine.get_states(["glider"])[0][0, 0] - start
    expect(abs(moved - 10 * dt / 2) <= 1e-9, "the distance glided in 10 halved steps",
           f"{10 * dt / 2!r} m", f"{moved!r} m")


def check_free_fall(ctx: CheckContext) -> None:
    """A ball dropped from rest falls z = z0 - g t²/2 for 1 s, within g·t·dt (twice what
    a first-order integrator lags by), and falls at g t within g·dt."""
    engine = ctx.engine
    g = float(-gravity(engine)[2])
    expect(g > 0, "gravity", "pointing down (-z)", gravity(engine))
    engine.spawn([group("sphere", ["ball"], [0, 0, 10.0])])
    dt = engine.timestep
    steps = round(1.0 / dt)
    engine.step(steps)
    t = steps * dt
    poses, twists = states(engine, ["ball"])
    expect_close(poses[0, 2:3], np.array([10.0 - g * t * t / 2]), g * t * dt,
                 f"height after falling {t:g} s")
    expect_close(twists[0, 2:3], np.array([-g * t]), g * dt, f"speed after falling {t:g} s")
    expect_close(poses[0, :2], np.zeros(2), 1e-12, "the sideways drift of a falling ball")


def check_resting_contact(ctx: CheckContext) -> None:
    """A ball dropped onto a plane comes to rest on it within 3 s: its centre one radius
    above the plane (within 5 mm), still to within 0.01 m/s and 0.01 rad/s."""
    engine = ctx.engine
    engine.spawn([ground(), group("sphere", ["ball"], [0, 0, 0.5])])
    engine.step(round(3.0 / engine.timestep))
    poses, twists = states(engine, ["ball"])
    expect_close(poses[0, 2:3], np.array([0.05]), REST_TOLERANCE, "the height of a ball "
                 "at rest on a plane")
    fastest = float(np.abs(twists[0]).max())
    expect(fastest <= REST_SPEED, "the twist of a ball at rest",
           f"every component within {REST_SPEED} (m/s, rad/s)", twists[0])


def check_static_bodies(ctx: CheckContext) -> None:
    """Static bodies never move: with balls falling onto them for 1 s, each keeps its pose
    bit for bit and a zero twist, and the ball on the static box stops on it."""
    engine = ctx.engine
    shapes = [s for s in engine.capabilities().body_shapes if s != "plane"]
    scenery = [group(s, [f"static {s}"], [2.0 * k, 0, 0.5], quaternion=TURNED, static=True)
               for k, s in enumerate(shapes)]
    scenery.append(group("box", ["shelf"], [0, 5.0, 0.5], size=(0.3, 0.3, 0.05),
                         static=True))
    balls = group("sphere", [f"on {s}" for s in shapes] + ["on shelf"],
                  [[2.0 * k, 0, 1.0] for k in range(len(shapes))] + [[0, 5.0, 0.7]])
    engine.spawn([*scenery, balls])
    names = [n for g in scenery for n in g.names]
    before = engine.get_states(names)[0]
    engine.step(round(1.0 / engine.timestep))
    poses, twists = states(engine, names)
    expect_identical(poses, before, "poses of static bodies after 1 s")
    expect_identical(twists, np.zeros_like(twists), "twists of static bodies")
    resting = engine.get_states(["on shelf"])[0][0, 2]
    expect_close(np.array([resting]), np.array([0.55 + 0.05]), REST_TOLERANCE,
                 "the height of a ball on a static shelf")


def _pile() -> list[BodyGroup]:
    """Spheres, boxes and a capsule made overlapping on a plane: they burst apart, collide
    and tumble, so any difference in the contact state shows within a few hundred steps."""
    return [ground(),
            group("sphere", [f"s{i}" for i in range(4)], [[0, 0, 0.05], [0.08, 0, 0.05],
                                                         [0.04, 0.06, 0.1], [0, 0.02, 0.14]]),
            group("box", ["b0", "b1"], [[0.1, 0.05, 0.05], [0.14, 0.08, 0.09]],
                  size=(0.05, 0.04, 0.03), quaternion=TURNED),
            group("capsule", ["cap"], [0.05, 0.1, 0.12], size=(0.03, 0.06),
                  twists=[0.2, 0, 0, 0, 0, 1.0])]


def _names(groups: list[BodyGroup]) -> list[str]:
    return [n for g in groups for n in g.names]


def _run(engine: Engine, pieces: list[int], names: list[str]) -> tuple[np.ndarray, ...]:
    for count in pieces:
        engine.step(count)
    return engine.get_states(names)


def _stack() -> BodyGroup:
    """Two layers of 50 balls, each ball exactly on top of one below: a touchy pile, whose
    fall shows any difference in the order contacts are solved."""
    i = np.arange(100)
    return group("sphere", [f"stacked{k}" for k in i], np.column_stack(
        [i % 10 * 0.104 + 2.0, i // 10 % 5 * 0.104, 0.3 + i // 50 * 0.104]), restitution=0.5)


def check_determinism(ctx: CheckContext) -> None:
    """The same scene stepped the same time gives bit-identical states in two engines,
    however the steps are split into calls (300 at once, or 1 + 7 + 42 + 250)."""
    scene = [*_pile(), _stack()]
    names = _names(scene)
    runs = []
    for pieces in ([300], [1, 7, 42, 250]):
        engine = ctx.fresh()
        engine.spawn([*_pile(), _stack()])
        runs.append(_run(engine, pieces, names))
    for part, first, second in zip(("poses", "twists"), *runs, strict=True):
        expect_identical(second, first, f"{part} of two identical runs")
    moved = np.abs(runs[0][0][:, :3] - np.vstack([g.poses for g in scene])[:, :3]).max()
    expect(moved > 0.05, "the pile's bodies", "moved apart", f"moved {moved:.3g} m at most")


def check_rewind(ctx: CheckContext) -> None:
    """Setting every body back to its created state, then reset_dynamics (the daemon's
    reset), restores that state and replays the first run bit for bit, whatever ran
    between."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_SET_STATE)
    scene = _pile()
    engine.spawn(scene)
    names = _names(scene)
    created = (np.vstack([g.poses for g in scene]),  # what the World keeps: what was given
               np.vstack([g.twists if g.twists is not None else np.zeros((len(g), 6))
                          for g in scene]))
    runs = []
    for steps in (250, 90, 250):
        runs.append(_run(engine, [steps], names))
        engine.set_states(names, *created)
        engine.reset_dynamics()
        back = states(engine, names)
        expect_poses(back[0], created[0], 1e-12, "poses after the rewind")
        expect_close(back[1], created[1], 1e-12, "twists after the rewind")
    for part, first, again in zip(("poses", "twists"), runs[0], runs[2], strict=True):
        expect_identical(again, first, f"{part} of a run replayed after a rewind")


def check_edits_keep_state(ctx: CheckContext) -> None:
    """Spawning, updating and deleting other bodies far away leave a moving body's
    trajectory bit-identical to one in a world without those edits."""
    skip_unless(ctx.engine, FEATURE_DELETE)
    faller = group("sphere", ["faller"], [0, 0, 10.0], twists=[0.3, 0, 0, 0, 0, 2.0])
    edited, plain = ctx.engine, ctx.fresh()
    for engine in (edited, plain):
        engine.spawn([faller])
        engine.step(50)
    edited.spawn([group("box", ["other"], [50, 50, 3.0]), ground("floor")])
    for engine in (edited, plain):
        engine.step(50)
    edited.delete(["other"])
    for engine in (edited, plain):
        engine.step(50)
    for part, got, want in zip(("pose", "twist"), edited.get_states(["faller"]),
                               plain.get_states(["faller"]), strict=True):
        expect_identical(got, want, f"the {part} of a body in a world edited around it")


def check_state_within(ctx: CheckContext) -> None:
    """state_within is False once a moving body is NaN, infinite, or past the limits
    (2e6 or 4e299 m away, moving at 2e5 m/s, spinning at 3e5 or 1e200 rad/s), True while
    static bodies alone stand far off, and True again after the bodies are set back and
    reset_dynamics."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_SET_STATE)
    engine.spawn([ground(), group("sphere", ["a", "b"], [[0, 0, 1], [1, 0, 1]]),
                  group("box", ["far"], [0, 0, -5e6], static=True)])
    start = engine.get_states(["a"])
    engine.step(1)
    expect(engine.state_within(*LIMITS) is True, "state_within of a sane world with a "
           "static body 5e6 m away", "True", False)
    bad = {"a NaN speed": (None, [math.nan, 0, 0, 0, 0, 0]),
           "an infinite spin": (None, [0, 0, 0, 0, -math.inf, 0]),
           "a body 4e299 m away": (poses_at([4e299, 0, 1]), None),
           "a body 2e6 m away": (poses_at([0, -2e6, 1]), None),
           "a speed of 2e5 m/s": (None, [0, 0, 2e5, 0, 0, 0]),
           "a spin of 3e5 rad/s": (None, [0, 0, 0, 0, 3e5, 0]),
           "a spin of 1e200 rad/s": (None, [0, 0, 0, 0, 0, 1e200])}
    for what, (pose, twist) in bad.items():
        engine.set_states(["a"], pose, None if twist is None else np.array([twist]))
        engine.step(1)
        expect(engine.state_within(*LIMITS) is False, f"state_within after {what}",
               "False", True)
        engine.set_states(["a"], *start)
        engine.reset_dynamics()
        engine.step(1)
        expect(engine.state_within(*LIMITS) is True, f"state_within after {what} was set "
               "back and reset_dynamics", "True", False)
