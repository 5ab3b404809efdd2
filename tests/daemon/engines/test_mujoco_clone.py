"""Clones of the MuJoCo engine (``Engine.clone``: forks and predictions): a clone goes on bit
for bit like its source (piles in contact and asleep, a KUKA under targets and a wrench, pool
churn before and after, changed parameters, a ball held awake on a crown), whatever either
of them does to itself afterwards, and snapshots like its source.
"""

from __future__ import annotations

import numpy as np
import pytest
from support.mujoco_worlds import (
    ALONG_Y,
    SEED,
    assert_same_runs,
    assert_same_world,
    bodies,
    floor,
    kuka,
    kuka_under_targets,
    pile,
    pile_requests,
    retarget,
    settled_pile,
    state,
    steps,
)

from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.protocol import BodyGroup, BodyProperties, OperationFailedError


@pytest.fixture
def engine() -> MujocoEngine:
    return MujocoEngine()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


def churn(engine: MujocoEngine) -> None:
    """Compiling and pooled spawns, deletes, updates and parameters: a world changed all over."""
    again = np.random.default_rng(SEED + 1)
    engine.spawn([bodies("sphere", [f"x{i}" for i in range(100)], (0.04,), again, height=1.0),
                  bodies("capsule", [f"c{i}" for i in range(3)], (0.02, 0.05), again)])
    engine.step(100)
    engine.delete(["b0", "x7", "c1"])
    engine.update(["s1"], BodyProperties(mass=0.3, friction=0.9))
    engine.set_params({"gravity": [0.5, 0.0, -9.0], "mujoco.condim": 6})
    engine.set_states(["s2"], np.array([[0, 0, 2.0, 0, 0, 0, 1]]), None)
    engine.step(100)


def test_a_pile_in_contact_and_asleep_goes_on_bit_identically(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    settled_pile(engine, rng)
    twin = engine.clone()
    assert_same_world(engine, twin)
    assert twin.data.ncon == engine.data.ncon
    assert_same_runs(engine, twin, pile_requests())


def test_a_kuka_under_targets_and_a_wrench_goes_on_bit_identically(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    joints = kuka_under_targets(engine, rng)
    twin = engine.clone()
    assert_same_world(engine, twin)
    assert twin.joints() == engine.joints()
    assert_same_runs(engine, twin, [steps(200), retarget(joints), steps(200), lambda e: e.delete(
        ["s1", "k/lbr_iiwa_link_0"]), steps(100), lambda e: e.restore_joints(), steps(50)])


def test_a_world_edited_in_its_pool_goes_on_exactly_and_later_edits_agree(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    """Binding and parking edit the compiled model alone: the clone copies that model, so
    it needs no recompile, and neither does its source."""
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(200)
    engine.delete([f"s{i}" for i in range(0, 70, 3)])  # parked
    pile(engine, rng, prefix="n", count=20)  # bound from the pool, no compile
    engine.step(200)
    assert engine.parked_edited
    twin = engine.clone()
    assert engine.parked_edited and twin.parked_edited
    assert_same_world(engine, twin)
    assert_same_runs(engine, twin, [churn, steps(200), lambda e: e.clear(),
                                    lambda e: e.spawn([floor()]),
                                    lambda e: pile(e, np.random.default_rng(SEED)),
                                    steps(300)])


def test_what_a_clone_does_leaves_its_source_alone_and_the_other_way_round(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    joints = kuka(engine)
    pile(engine, rng)
    engine.set_wrenches(["b2"], np.array([[0, 0, 3.0, 0, 0, 0]]), None)
    engine.step(300)
    edited, witness = engine.clone(), engine.clone()
    churn(edited)
    edited.set_joint_targets(joints, "effort", np.ones(len(joints)), *np.zeros((2, len(joints))),
                             np.full(len(joints), np.inf))
    edited.clear_wrenches(None)
    edited.step(300)
    edited.clear()
    assert sorted(engine.entities) == sorted(witness.entities)
    assert_same_world(engine, witness)
    assert_same_runs(engine, witness, [steps(300)])
    before = state(edited)
    churn(engine)
    engine.clear()
    np.testing.assert_array_equal(state(edited), before)


def test_a_ball_held_awake_on_a_crown_stays_held_and_is_let_go_alike(
        engine: MujocoEngine) -> None:
    pin = BodyGroup(shape="cylinder", size=(0.1, 0.3), names=["pin"],
                    poses=np.array([[0, 0, 1.0, *ALONG_Y]]), static=True)
    ball = BodyGroup(shape="sphere", size=(0.045,), names=["a"], mass=0.38,
                     poses=np.array([[0, 0, 1.145, 0, 0, 0, 1]]))
    engine.spawn([floor(), pin, ball])
    engine.step(500)
    assert engine.sleep_guard is not None and engine.sleep_guard.held
    twin = engine.clone()
    assert twin.sleep_guard is not None and twin.sleep_guard.held == engine.sleep_guard.held
    assert_same_runs(engine, twin, [steps(1000)] * 4)
    assert not engine.sleep_guard.held


def test_changed_parameters_travel_and_later_changes_agree(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.set_params({"timestep": 1 / 700, "default_friction": 0.6180339887,
                       "mujoco.cone": "pyramidal", "mujoco.threads": 2})
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(300)
    twin = engine.clone()
    assert twin.get_params() == engine.get_params()
    assert_same_runs(engine, twin, [steps(200), lambda e: e.set_params(
        {"mujoco.wake_balanced": False, "mujoco.solver": "newton"}), steps(100)])


def test_a_clone_of_a_clone_goes_on_after_its_sources_closed(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(400)
    twin = engine.clone()
    grandchild = twin.clone()
    engine.step(300)
    expected = state(engine)
    engine.close()
    twin.close()
    del engine, twin
    grandchild.step(300)
    np.testing.assert_array_equal(state(grandchild), expected)


def test_a_clone_snapshots_as_its_source(engine: MujocoEngine,
                                         rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    kuka(engine)
    pile(engine, rng)
    engine.step(200)
    engine.delete(["s1", "s2"])
    pile(engine, rng, prefix="n", count=2)
    engine.step(100)
    twin = engine.clone()
    assert twin.snapshot() == engine.snapshot()


def test_a_broken_world_is_not_cloned(engine: MujocoEngine) -> None:
    engine.broken = True  # as a failed step leaves it
    with pytest.raises(OperationFailedError, match="broken"):
        engine.clone()
