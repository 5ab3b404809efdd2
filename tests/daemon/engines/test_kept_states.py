"""States kept in memory (``Engine.save_state``/``load_state``) on ODE and DART: set back into the
same world, they go on bit for bit as the world went on from the moment they were kept, and
as the portable path (a snapshot restored into a fresh engine) goes on: a pile in contact
with sleepers, a KUKA under targets and a wrench. A world whose bodies changed refuses it.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.mujoco_worlds import KUKA, SEED, bodies, floor

from galton.daemon.engines.dart.engine import DartEngine
from galton.daemon.engines.ode.engine import OdeEngine
from galton.daemon.world.model_files import resolve_model
from galton.protocol import BodyGroup

STEPS = 400


Kept = OdeEngine | DartEngine


def state(engine: Kept) -> np.ndarray:
    """Every entity's pose and twist, and every driven joint's state and effort."""
    names = sorted(engine._bodies)
    joints = [j.name for j in engine.joints() if j.type in ("revolute", "prismatic")]
    parts = [*engine.get_states(names)]
    if joints:
        parts += engine.get_joint_states(joints)
    return np.concatenate(parts, axis=None)


@pytest.fixture(scope="module", params=[OdeEngine, DartEngine], ids=["ode", "dart"])
def world(request: pytest.FixtureRequest) -> Iterator[Kept]:
    """A pile on a floor, part of it asleep, beside a KUKA holding targets under a wrench
    (one for the module: each test starts from a state it keeps; the last one spawns)."""
    engine: Kept = request.param()
    rng = np.random.default_rng(SEED)
    engine.spawn([floor(), bodies("sphere", [f"s{i}" for i in range(30)], (0.04,), rng),
                  bodies("box", [f"b{i}" for i in range(8)], (0.05, 0.04, 0.03), rng)])
    text = resolve_model("urdf", KUKA.read_text(), str(KUKA), [])
    engine.load_model("urdf", text, None, "k/")
    joints = [j.name for j in engine.joints() if j.type == "revolute"]
    n = len(joints)
    engine.set_joint_targets(joints, "position", np.linspace(-0.5, 0.5, n), np.full(n, 300.0),
                             np.full(n, 20.0), np.full(n, 200.0))
    engine.set_wrenches(["s0"], np.array([[0, 0, 0.5, 0, 0, 0.1]]), None)
    engine.step(1500)
    yield engine
    engine.close()


def test_a_kept_state_goes_on_bit_for_bit_as_the_world_and_the_portable_path(
        world: Kept) -> None:
    if isinstance(world, OdeEngine):
        assert any(not b.awake for b in world._moving)  # sleepers in the pile
    kept = world.save_state()
    blob = world.snapshot()  # the portable path, at the same moment
    world.step(STEPS)
    expected = state(world)
    portable = type(world)()
    try:
        portable.restore(blob)
        portable.step(STEPS)
        np.testing.assert_array_equal(state(portable), expected)
    finally:
        portable.close()
    for _ in range(2):  # however often it is loaded
        assert world.load_state(kept)
        world.step(STEPS)
        np.testing.assert_array_equal(state(world), expected)


def test_targets_and_wrenches_changed_after_keeping_are_put_back(world: Kept) -> None:
    kept = world.save_state()
    world.step(STEPS)
    expected = state(world)
    assert world.load_state(kept)
    joints = [j.name for j in world.joints() if j.type == "revolute"]
    world.set_joint_targets(joints[:2], "velocity", np.ones(2), np.zeros(2), np.full(2, 5.0),
                            np.full(2, 50.0))
    world.clear_wrenches(None)
    world.set_wrenches(["s3"], np.array([[0, 0, 3.0, 0, 0, 0]]), None)
    world.step(50)
    assert world.load_state(kept)
    world.step(STEPS)
    np.testing.assert_array_equal(state(world), expected)


def test_a_clone_takes_the_kept_state_as_a_slots_twin_does(world: Kept) -> None:
    kept = world.save_state()
    twin = world.clone()
    try:
        world.step(STEPS)
        assert twin.load_state(kept)
        twin.step(STEPS)
        np.testing.assert_array_equal(state(twin), state(world))
    finally:
        twin.close()


def test_a_world_whose_bodies_changed_refuses_it(world: Kept) -> None:
    kept = world.save_state()
    world.spawn([BodyGroup("sphere", (0.03,), ["new"],
                           np.array([[0, 0, 2.0, 0, 0, 0, 1]]))])
    before = state(world)
    assert not world.load_state(kept)
    np.testing.assert_array_equal(state(world), before)
