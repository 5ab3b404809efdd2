"""The futures runner's seam (daemon/world/futures.py), in process on every engine: forks
of one world, each with its own body properties (what a calibration's candidates need) and
timed actions, stepped together; a future with nothing of its own goes on exactly as a
fork stepped alone, and the source is never touched. And the kept-state fast path
(daemon/world/states.py): refused once the structure changed."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from galton.daemon.core.limits import DEFAULT_LIMITS
from galton.daemon.engines import create_engine
from galton.daemon.world import states
from galton.daemon.world.futures import FutureSet, FutureSpec, spread
from galton.daemon.world.slots import Slot, SnapshotSlots
from galton.daemon.world.snapshot import clone_of
from galton.daemon.world.world import World
from galton.protocol import BodyProperties
from galton.protocol.model import BodyGroup

ENGINES = ("mujoco", "pybullet", "ode", "dart")
BALLS = ["a", "b"]
STEPS = 60


@pytest.fixture(params=ENGINES)
def world(request: pytest.FixtureRequest) -> Iterator[World]:
    made = World(create_engine(request.param), "w", DEFAULT_LIMITS)
    floor = np.array([[0, 0, 0, 0, 0, 0, 1.0]])
    made.spawn([BodyGroup("plane", (5.0, 5.0), ["floor"], floor, static=True)])
    poses = np.array([[0, 0, 0.1, 0, 0, 0, 1.0], [0.5, 0, 0.1, 0, 0, 0, 1.0]])
    made.spawn([BodyGroup("sphere", (0.1,), BALLS, poses, mass=1.0, friction=0.5)])
    made.step(5)
    yield made
    made.engine.close()


def push(world: World) -> None:
    world.wrenches.apply(world.engine, ["a"], np.array([[20.0, 0, 0, 0, 0, 0]]), None,
                         0.05, world.step_index)


def test_each_future_has_its_own_properties_and_actions(world: World) -> None:
    before = world.get_states(BALLS)[0].copy()
    heavy = [(["a"], BodyProperties(mass=4.0))]
    specs = [FutureSpec(events=[(10, push)]), FutureSpec(overrides=heavy, events=[(10, push)]),
             FutureSpec()]
    futures = FutureSet.fork(world, specs, DEFAULT_LIMITS, threads=2)
    try:
        futures.step(STEPS // 2)
        futures.step(STEPS - STEPS // 2)  # an action lands on its step however cut
        ends = futures.positions(BALLS)
        masses = [f.engine.properties(["a"])[0, 0] for f in futures.worlds]
    finally:
        futures.close()
    np.testing.assert_array_equal(world.get_states(BALLS)[0], before)  # source untouched
    assert masses == [1.0, 4.0, 1.0]
    pushed, pushed_heavy, still = ends[:, 0, 0] - before[0, 0]
    assert pushed > pushed_heavy > 0 and abs(still) < 1e-6
    alone = clone_of(world, "alone", DEFAULT_LIMITS)
    try:
        alone.step(10)
        push(alone)
        alone.step(STEPS - 10)
        np.testing.assert_array_equal(alone.get_states(BALLS)[0][:, :3], ends[0])
    finally:
        alone.engine.close()
    assert spread(ends).shape == (2,) and spread(ends[[0, 0]]).max() == 0.0


def test_a_kept_state_is_refused_once_the_structure_changed(world: World) -> None:
    kept = states.save(world)
    if kept is None:
        pytest.skip(f"{world.engine.name} keeps no state in memory (portable path)")
    world.step(20)
    assert states.load(world, kept) and world.step_index == 5
    world.update(["b"], BodyProperties(friction=0.9))
    assert not states.fits(world, kept) and not states.load(world, kept)
    assert world.step_index == 5


def test_a_replaced_slot_lends_its_memory_and_nothing_else(world: World) -> None:
    """A slot replaced by a newer snapshot gives its engine memory to the next one; the
    newer slot still replays bit for bit after more snapshots are taken."""
    slots = SnapshotSlots(DEFAULT_LIMITS)

    def keep(name: str) -> None:
        kept = states.save(world)
        slots.keep(Slot(name, world.name, world.engine.name, None, world.step_index,
                        world.sim_time, len(world.entities), kept), world)
    if states.save(world) is None:
        pytest.skip(f"{world.engine.name} keeps no state in memory (portable path)")
    keep("s")
    world.step(7)
    keep("s")  # replaces the first: its memory is lent to the next snapshot
    newer = slots.get("s")
    world.step(10)
    expected = world.get_states(BALLS)
    keep("t")  # in the first's memory
    world.step(3)
    keep("t")
    assert newer.state is not None and states.load(world, newer.state)
    world.step(10)
    np.testing.assert_array_equal(world.get_states(BALLS)[0], expected[0])
    np.testing.assert_array_equal(world.get_states(BALLS)[1], expected[1])
    slots.close()
