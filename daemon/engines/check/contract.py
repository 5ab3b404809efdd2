"""Engine checks of the interface contract: methods and the shapes they return, bodies of
every shape, states, properties, delete and clear.

Each check gets a fresh engine from its ``CheckContext`` and fails with ``CheckFailedError``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from galton.daemon.engines.base import (
    FEATURE_DELETE,
    FEATURE_SET_STATE,
    FEATURE_UPDATE_FRICTION,
    FEATURE_UPDATE_MASS,
    FEATURE_UPDATE_RESTITUTION,
    KNOWN_FEATURES,
    Engine,
)
from galton.daemon.engines.check.support import (
    DENSITY,
    TURNED,
    CheckContext,
    Snapshot,
    expect,
    expect_array,
    expect_close,
    expect_identical,
    expect_poses,
    expect_raises,
    group,
    poses_at,
    skip_unless,
    states,
)
from galton.protocol import BODY_SHAPES, BodyProperties, Capabilities, NotFoundError

STATE_ATOL = 1e-9  # what a pose or twist set may lose on its way into an engine and back
TWIST = (0.3, -0.2, 0.5, 1.0, -2.0, 0.5)
FEATURES = KNOWN_FEATURES


def check_interface(ctx: CheckContext) -> None:
    """Every abstract method of Engine is there; the engine's name, capabilities (shapes
    and features the protocol knows), parameters (each with a default, all of them in
    get_params) and timestep (positive, the "timestep" parameter's value) describe it."""
    engine = ctx.engine
    missing = sorted(name for name in getattr(Engine, "__abstractmethods__", ())
                     if not callable(getattr(engine, name, None)) and name != "timestep")
    expect(not missing, "Engine's methods", "all of them", f"{missing} missing")
    expect(isinstance(getattr(engine, "name", None), str), "the engine's name",
           "a str class attribute", getattr(engine, "name", None))
    caps = engine.capabilities()
    expect(isinstance(caps, Capabilities), "capabilities()", "a Capabilities", caps)
    expect(caps.engine == engine.name, "capabilities().engine", repr(engine.name), caps.engine)
    unknown = sorted(set(caps.body_shapes) - set(BODY_SHAPES))
    expect(not unknown, "capabilities().body_shapes", f"shapes among {BODY_SHAPES}", unknown)
    unknown = sorted(set(caps.features) - set(FEATURES))
    expect(not unknown, "capabilities().features", f"features among {FEATURES}", unknown)
    params = engine.get_params()
    expect(set(caps.params) == set(params), "get_params()'s names",
           f"those of capabilities().params, {sorted(caps.params)}", sorted(params))
    no_default = [k for k, spec in caps.params.items() if "default" not in spec]
    expect(not no_default, "capabilities().params", "a default for each", no_default)
    dt = engine.timestep
    expect(isinstance(dt, float) and math.isfinite(dt) and dt > 0, "timestep",
           "a positive finite float", dt)
    expect(params.get("timestep", dt) == dt, 'get_params()["timestep"]', repr(dt),
           params.get("timestep"))


def check_return_shapes(ctx: CheckContext) -> None:
    """States and properties come as float64 arrays of (n, 7), (n, 6) and (n, 3), for no
    bodies as for some; state_within answers a bool; spawn and step return None."""
    engine = ctx.engine
    states(engine, [])
    expect_array(engine.properties([]), (0, 3), "properties of no bodies")
    answer = engine.state_within(1e6, 1e5)
    expect(answer is True, "state_within of an empty world", "True (a bool)", answer)
    names = ["first", "second"]
    expect(engine.spawn([group("sphere", names, [[0, 0, 1], [1, 0, 1]])]) is None,
           "spawn's result", "None", "a value")
    expect(engine.step(1) is None, "step's result", "None", "a value")
    states(engine, names)
    expect_array(engine.properties(names), (2, 3), "properties of 2 bodies")
    answer = engine.state_within(1e6, 1e5)
    expect(answer is True, "state_within of 2 falling balls", "True (a bool)", answer)


def check_spawn_shapes(ctx: CheckContext) -> None:
    """Every shape the engine lists spawns static and dynamic (a plane static only), in
    one batch, turned and, if dynamic, moving: each body reads back at the pose and with
    the twist it was given (a static body with none), in the order asked for."""
    engine = ctx.engine
    groups, twists = [], []
    for k, shape in enumerate(engine.capabilities().body_shapes):
        if shape == "plane":
            groups.append(group(shape, ["plane"], [0, 0, -1.0], static=True))
            twists.append(np.zeros(6))
            continue
        groups.append(group(shape, [f"static {shape}"], [k, 3.0, 2.0], quaternion=TURNED,
                            static=True))
        groups.append(group(shape, [f"moving {shape}"], [k, 0.0, 2.0], quaternion=TURNED,
                            twists=TWIST))
        twists.extend([np.zeros(6), np.array(TWIST)])
    engine.spawn(groups)
    names = [n for g in groups for n in g.names][::-1]  # read in another order than made
    poses, got = states(engine, names)
    expect_poses(poses, np.vstack([g.poses for g in groups])[::-1], STATE_ATOL,
                 "poses of spawned bodies")
    expect_close(got, np.vstack(twists)[::-1], STATE_ATOL, "twists of spawned bodies")


def check_state_round_trip(ctx: CheckContext) -> None:
    """set_states then get_states gives back what was set; a pose alone keeps each body's
    twist, a twist alone its pose; bodies not named keep theirs."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_SET_STATE)
    engine.spawn([group("box", ["a", "b", "c"], [[0, 0, 1], [1, 0, 1], [2, 0, 1]])])
    untouched = engine.get_states(["c"])
    pose, twist = poses_at([[2.0, 3.0, 4.0], [-1.0, 0.5, 2.0]], TURNED), np.array(
        [TWIST, [1.0, 0, 0, 0, 3.0, 0]])
    engine.set_states(["b", "a"], pose, twist)
    got_pose, got_twist = states(engine, ["b", "a"])
    expect_poses(got_pose, pose, STATE_ATOL, "poses set")
    expect_close(got_twist, twist, STATE_ATOL, "twists set")
    moved = poses_at([[5.0, 5.0, 5.0], [6.0, 5.0, 5.0]])
    engine.set_states(["b", "a"], moved, None)
    got_pose, got_twist = states(engine, ["b", "a"])
    expect_poses(got_pose, moved, STATE_ATOL, "poses set alone")
    expect_close(got_twist, twist, STATE_ATOL, "twists after a pose set alone")
    engine.set_states(["a"], None, np.zeros((1, 6)))
    got_pose, got_twist = states(engine, ["a"])
    expect_poses(got_pose, moved[1:], STATE_ATOL, "a pose after a twist set alone")
    expect_close(got_twist, np.zeros((1, 6)), STATE_ATOL, "a twist set alone")
    for got, want in zip(engine.get_states(["c"]), untouched, strict=True):
        expect_identical(got, want, "the state of a body not named")


def check_properties(ctx: CheckContext) -> None:
    """properties() reads back what the engine simulates: given values as given, a mass
    left None as 1000 kg/m³ times the volume, no mass (NaN) for a static body, finite
    non-negative friction and restitution always, and each update's new values."""
    engine = ctx.engine
    engine.spawn([group("box", ["plain"], [0, 0, 1]),
                  group("capsule", ["given"], [1, 0, 1], mass=2.5, friction=0.9,
                        restitution=0.25),
                  group("sphere", ["fixed"], [2, 0, 1], static=True)])
    names = ["plain", "given", "fixed"]
    values = expect_array(engine.properties(names), (3, 3), "properties of 3 bodies")
    box_mass = DENSITY * 8 * 0.05 * 0.1 * 0.15
    expect_close(values[0, :1], np.array([box_mass]), 1e-9 * box_mass, "a default mass")
    expect_close(values[1], np.array([2.5, 0.9, 0.25]), 1e-12, "given mass, friction, "
                 "restitution")
    expect(math.isnan(values[2, 0]), "a static body's mass", "NaN", values[2, 0])
    surfaces = values[:, 1:]
    expect(bool(np.isfinite(surfaces).all() and (surfaces >= 0).all()),
           "friction and restitution", "finite and >= 0", surfaces)
    edits = {FEATURE_UPDATE_MASS: ("mass", BodyProperties(mass=1.5), 0, 1.5),
             FEATURE_UPDATE_FRICTION: ("friction", BodyProperties(friction=0.7), 1, 0.7),
             FEATURE_UPDATE_RESTITUTION: ("restitution", BodyProperties(restitution=0.4), 2,
                                          0.4)}
    features = engine.capabilities().features
    for feature, (field, props, column, value) in edits.items():
        if feature in features:
            engine.update(["plain"], props)
            got = engine.properties(["plain"])[0, column]
            expect(got == value, f"{field} after an update", repr(value), got)


def check_delete(ctx: CheckContext) -> None:
    """delete removes exactly the bodies named: they are unknown after (NotFoundError), the
    others keep their state bit for bit, and a freed name can be spawned again."""
    engine = ctx.engine
    skip_unless(engine, FEATURE_DELETE)
    engine.spawn([group("sphere", ["a", "b", "c"], [[0, 0, 1], [1, 0, 1], [2, 0, 1]],
                        twists=[TWIST] * 3)])
    engine.step(3)
    kept = engine.get_states(["b"])
    engine.delete(["c", "a"])
    for got, want in zip(engine.get_states(["b"]), kept, strict=True):
        expect_identical(got, want, "the state of a body kept by a delete")
    for name in ("a", "c"):
        with expect_raises(NotFoundError, f"get_states of deleted {name!r}"):
            engine.get_states([name])
    engine.spawn([group("box", ["a"], [5, 5, 5])])
    expect_poses(engine.get_states(["a"])[0], poses_at([5, 5, 5]), STATE_ATOL,
                 "a body spawned under a freed name")


def check_clear(ctx: CheckContext) -> None:
    """clear empties the world and keeps the parameters; names are free again after it."""
    engine = ctx.engine
    engine.spawn([group("sphere", ["a", "b"], [[0, 0, 1], [1, 0, 1]])])
    engine.step(2)
    params = engine.get_params()
    engine.clear()
    with expect_raises(NotFoundError, "get_states of a body after clear"):
        engine.get_states(["a"])
    expect(engine.get_params() == params, "parameters after clear", "unchanged",
           engine.get_params())
    engine.spawn([group("sphere", ["a"], [0, 0, 3.0])])
    expect_poses(engine.get_states(["a"])[0], poses_at([0, 0, 3.0]), STATE_ATOL,
                 "a body spawned after clear")
    expect(engine.state_within(1e6, 1e5), "state_within after clear", "True", False)


def check_unknown_names(ctx: CheckContext) -> None:
    """A batch naming an unknown body is refused whole with NotFoundError and changes
    nothing (the World checks names first; the engine must not half-apply it anyway)."""
    engine = ctx.engine
    engine.spawn([group("sphere", ["a", "b"], [[0, 0, 1], [1, 0, 1]], twists=[TWIST] * 2)])
    before = Snapshot.of(engine, ["a", "b"])
    features = engine.capabilities().features
    calls: dict[str, Callable[[], object]] = {
        "get_states": lambda: engine.get_states(["a", "ghost"]),
        "properties": lambda: engine.properties(["a", "ghost"]),
    }
    if FEATURE_SET_STATE in features:
        calls["set_states"] = lambda: engine.set_states(
            ["a", "ghost"], poses_at([[9, 9, 9]] * 2), np.zeros((2, 6)))
    if FEATURE_UPDATE_FRICTION in features:
        calls["update"] = lambda: engine.update(["a", "ghost"], BodyProperties(friction=0.123))
    if FEATURE_DELETE in features:
        calls["delete"] = lambda: engine.delete(["a", "ghost"])
    for what, call in calls.items():
        with expect_raises(NotFoundError, f"{what} naming an unknown body"):
            call()
        before.expect_same(engine, f"after a refused {what}")
