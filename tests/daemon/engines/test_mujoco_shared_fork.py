"""Forks of the MuJoCo engine share their source's spec and compiled model, read-only, and
copy only the data (clone.py): the first change to what they share, on either side, takes
its own copy first. A structure change or an edited model array (joint targets' gains, the
sleep guard's sleep policies) never leaks from a fork into its source or the other way
round, and the fork still goes on bit for bit as its source.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from support.mujoco_worlds import (
    ALONG_Y,
    SEED,
    arrays,
    assert_same_runs,
    floor,
    kuka,
    pile,
    state,
    steps,
)

from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.protocol import BodyGroup, BodyProperties

Edit = Callable[[MujocoEngine], None]


def model_arrays(engine: MujocoEngine) -> dict[str, np.ndarray]:
    """Every array of its model, copied (to compare with what it held before)."""
    return {n: v.copy() for n, v in arrays(engine.model).items()}


def assert_unchanged(engine: MujocoEngine, before: tuple[str, dict[str, np.ndarray], set[str]]
                     ) -> None:
    xml, model, names = before
    assert engine.mj_spec.to_xml() == xml
    now = arrays(engine.model)
    assert [n for n in model if not np.array_equal(model[n], now[n], equal_nan=True)] == []
    assert set(engine.entities) == names


def seen(engine: MujocoEngine) -> tuple[str, dict[str, np.ndarray], set[str]]:
    return engine.mj_spec.to_xml(), model_arrays(engine), set(engine.entities)


@pytest.fixture
def world() -> tuple[MujocoEngine, list[str]]:
    engine = MujocoEngine()
    engine.spawn([floor()])
    joints = kuka(engine)
    pile(engine, np.random.default_rng(SEED), count=20)
    engine.step(200)
    return engine, joints


def edits(joints: list[str]) -> dict[str, Edit]:
    n = len(joints)
    ball = BodyGroup(shape="sphere", size=(0.03,), names=["new"],
                     poses=np.array([[0, 0, 2.0, 0, 0, 0, 1]]))
    return {
        "spawn": lambda e: e.spawn([ball]),
        "delete": lambda e: e.delete(["s3", "b1"]),
        "update": lambda e: e.update(["s1"], BodyProperties(mass=0.7, friction=0.2)),
        "set_params": lambda e: e.set_params({"gravity": [0.0, 1.0, -9.0]}),
        "static pose": lambda e: e.set_states(["floor"], np.array([[0, 0, -0.1, 0, 0, 0, 1]]),
                                              None),
        "joint targets": lambda e: e.set_joint_targets(
            joints, "position", np.full(n, 0.3), np.full(n, 200.0), np.full(n, 10.0),
            np.full(n, 50.0)),
        "clear": lambda e: e.clear(),
    }


EDITS = list(edits([]))


def test_a_fork_shares_the_structure_and_copies_the_data(
        world: tuple[MujocoEngine, list[str]]) -> None:
    engine, _ = world
    fork = engine.clone()
    assert fork.mj_spec is engine.mj_spec and fork.model is engine.model
    assert fork.data is not engine.data
    fork.step(100)  # stepping changes nothing shared
    assert fork.model is engine.model


@pytest.mark.parametrize("edit", EDITS)
def test_a_forks_edit_never_reaches_its_source(world: tuple[MujocoEngine, list[str]],
                                                edit: str) -> None:
    engine, joints = world
    witness = engine.clone()
    before = seen(engine)
    fork = engine.clone()
    edits(joints)[edit](fork)
    fork.step(50)
    assert fork.model is not engine.model
    assert_unchanged(engine, before)
    assert witness.model is engine.model  # the others still share
    assert_same_runs(engine, witness, [steps(150)])


@pytest.mark.parametrize("edit", EDITS)
def test_a_sources_edit_never_reaches_its_fork(world: tuple[MujocoEngine, list[str]],
                                                edit: str) -> None:
    engine, joints = world
    fork, witness = engine.clone(), engine.clone()
    before = seen(fork)
    edits(joints)[edit](engine)
    engine.step(50)
    assert_unchanged(fork, before)
    assert fork.model is witness.model and fork.mj_spec is witness.mj_spec
    assert_same_runs(fork, witness, [steps(100), edits(joints)[edit], steps(100)])


def test_the_sleep_guards_sleep_policies_stay_in_the_fork(world: tuple[MujocoEngine, list[str]]
                                                            ) -> None:
    engine = MujocoEngine()
    pin = BodyGroup(shape="cylinder", size=(0.1, 0.3), names=["pin"],
                    poses=np.array([[0, 0, 1.0, *ALONG_Y]]), static=True)
    ball = BodyGroup(shape="sphere", size=(0.045,), names=["a"], mass=0.38,
                     poses=np.array([[0, 0, 1.145, 0, 0, 0, 1]]))
    engine.spawn([floor(), pin, ball])
    fork = engine.clone()
    before = engine.model.tree_sleep_policy.copy()
    fork.step(500)
    assert fork.sleep_guard is not None and fork.sleep_guard.held  # it wrote a sleep policy
    assert fork.model is not engine.model
    np.testing.assert_array_equal(engine.model.tree_sleep_policy, before)
    engine.step(500)
    np.testing.assert_array_equal(state(engine), state(fork))


def test_the_last_holder_copies_nothing(world: tuple[MujocoEngine, list[str]]) -> None:
    engine, _ = world
    fork = engine.clone()
    spec = engine.mj_spec
    fork.close()
    engine.update(["s1"], BodyProperties(mass=0.7))
    assert engine.mj_spec is spec and engine.sharing is None


def test_forks_replay_bit_for_bit_through_edits(world: tuple[MujocoEngine, list[str]]) -> None:
    engine, joints = world
    a, b = engine.clone(), engine.clone()
    requests = [steps(100), *[r for e in ("joint targets", "spawn", "delete", "set_params")
                              for r in (edits(joints)[e], steps(60))]]
    assert_same_runs(a, b, requests)
    expected = state(a)
    for request in requests:
        request(engine)
    np.testing.assert_array_equal(state(engine), expected)
