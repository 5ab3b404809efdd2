"""Snapshots of the MuJoCo engine: a world restored into a fresh engine continues bit for bit
like its source (piles in contact and asleep, a KUKA under targets and a wrench, pool churn,
changed parameters, a ball held awake on a pin's crown), as often as it is restored, after
its source has closed and through msgpack; malformed snapshots are refused with typed
errors.
"""

from __future__ import annotations

import contextlib
import copy
import math
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np
import pytest
from support.mujoco_worlds import (
    ALONG_Y,
    SEED,
    assert_same_runs,
    assert_same_world,
    bodies,
    carried,
    floor,
    kuka,
    kuka_under_targets,
    pile,
    pile_requests,
    restored,
    retarget,
    settled_pile,
    state,
    steps,
)

from galton.daemon.engines.base import FEATURE_SNAPSHOT
from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.protocol import BodyGroup, BodyProperties, InvalidArgumentError
from galton.protocol.mesh import prism_mesh


@pytest.fixture
def engine() -> MujocoEngine:
    return MujocoEngine()


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(SEED)


def test_the_snapshot_feature_is_listed(engine: MujocoEngine) -> None:
    assert FEATURE_SNAPSHOT in engine.capabilities().features


def test_a_pile_in_contact_and_asleep_continues_bit_identically(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    settled_pile(engine, rng)
    copy_ = restored(engine.snapshot())
    assert_same_runs(engine, copy_, pile_requests())


def test_a_kuka_with_position_targets_and_a_wrench_continues_bit_identically(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    joints = kuka_under_targets(engine, rng)
    copy_ = restored(engine.snapshot())
    assert_same_world(engine, copy_)
    assert [j.mode for j in copy_.joints()] == [j.mode for j in engine.joints()]
    assert_same_runs(engine, copy_, [steps(200), retarget(joints), steps(200),
                                     lambda e: e.set_joint_states(joints[3:], np.full(
                                         len(joints) - 3, 0.2), None), steps(100),
                                     lambda e: e.restore_joints(), steps(50)])


def test_spawn_and_delete_churn_continues_and_later_edits_agree(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(200)
    engine.delete([f"s{i}" for i in range(0, 70, 3)])  # parked
    pile(engine, rng, prefix="n", count=20)  # bound from the pool, no compile
    engine.step(200)
    copy_ = restored(engine.snapshot())
    assert_same_world(engine, copy_)
    again = np.random.default_rng(SEED + 1)
    later = [bodies("sphere", [f"x{i}" for i in range(100)], (0.04,), again, height=1.0),
             bodies("sphere", [f"y{i}" for i in range(5)], (0.04,), again, height=1.0)]
    assert_same_runs(engine, copy_, [
        steps(100), lambda e: e.spawn(later), steps(200),
        lambda e: e.delete(["b0", "ns1", "x7"]), steps(100),
        lambda e: e.update(["s1"], BodyProperties(mass=0.3)), steps(100),
        lambda e: e.clear(), lambda e: e.spawn([floor()]), lambda e: pile(
            e, np.random.default_rng(SEED)), steps(300)])


def test_a_snapshot_after_pool_edits_keeps_the_sources_state_and_sleepers(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    """Binding and parking edit the compiled model alone, so the snapshot recompiles it
    first (as the restore compiles it), carrying the data over exactly."""
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(1500)
    engine.delete(["s1", "s2"])
    pile(engine, rng, prefix="n", count=2)  # bound from the pool
    engine.step(100)
    before = {n: a.copy() for n, a in carried(engine.data).items()}
    asleep = int(np.count_nonzero(engine.data.tree_asleep >= 0))
    assert asleep and engine.parked_edited
    engine.snapshot()
    after = carried(engine.data)
    assert [n for n in before if not np.array_equal(before[n], after[n], equal_nan=True)] == []
    assert not engine.parked_edited


def test_a_second_snapshot_sees_edits_since_the_first_and_restored_worlds_snapshot_alike(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    """The spec's MJCF is kept between snapshots: edits of the spec must renew it."""
    pin = BodyGroup(shape="cylinder", size=(0.05, 0.3), names=["pin"],
                    poses=np.array([[0, 0, 0.2, *ALONG_Y]]), static=True)
    engine.spawn([floor(), pin])
    pile(engine, rng)
    engine.step(200)
    engine.snapshot()
    engine.update(["s0", "b1"], BodyProperties(friction=0.9, restitution=0.2,
                                               rgba=(0.1, 0.2, 0.3, 1.0)))
    engine.set_params({"mujoco.condim": 6, "default_friction": 0.7})
    engine.set_states(["pin"], np.array([[0.1, 0, 0.25, *ALONG_Y]]), None)
    engine.step(50)
    second = restored(engine.snapshot())
    assert_same_world(engine, second)
    third = restored(second.snapshot())
    assert_same_world(engine, third)
    assert_same_runs(engine, third, [steps(300)])
    second.step(300)
    np.testing.assert_array_equal(state(second), state(engine))


def test_changed_parameters_travel_and_later_changes_agree(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.set_params({"timestep": 1 / 700, "default_friction": 0.6180339887,
                       "mujoco.solref": [0.0123456789, 0.9], "mujoco.cone": "pyramidal",
                       "mujoco.sleep_tolerance": 0.0071})
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(300)
    copy_ = restored(engine.snapshot())
    assert copy_.get_params() == engine.get_params()
    assert_same_runs(engine, copy_, [
        steps(200), lambda e: e.set_params({"default_restitution": 0.4321, "gravity": [
            0.1, 0.0, -9.7]}), steps(300), lambda e: e.set_params(
                {"mujoco.wake_balanced": False, "mujoco.solver": "newton"}), steps(100)])


def test_a_ball_held_awake_on_a_crown_stays_held_and_is_let_go_alike(
        engine: MujocoEngine) -> None:
    pin = BodyGroup(shape="cylinder", size=(0.1, 0.3), names=["pin"],
                    poses=np.array([[0, 0, 1.0, *ALONG_Y]]), static=True)
    ball = BodyGroup(shape="sphere", size=(0.045,), names=["a"], mass=0.38,
                     poses=np.array([[0, 0, 1.145, 0, 0, 0, 1]]))
    engine.spawn([floor(), pin, ball])
    engine.step(500)
    assert engine.sleep_guard is not None and engine.sleep_guard.held
    copy_ = restored(engine.snapshot())
    assert copy_.sleep_guard is not None and copy_.sleep_guard.held == engine.sleep_guard.held
    assert_same_runs(engine, copy_, [steps(1000)] * 4)
    assert not engine.sleep_guard.held


def test_a_prism_mesh_world_restores_and_continues_bit_identically(
        engine: MujocoEngine) -> None:
    """The paper-mesh board's pins: MJCF's six digits moved a prism's vertices, and MuJoCo
    then refused its geom's size ("computed from the mesh"); the vertices travel exactly."""
    vertices, faces = prism_mesh(0.1, 0.05, 6)
    pin = BodyGroup(shape="mesh", size=(), names=["pin"], static=True,
                    poses=np.array([[0, 0, 0.5, *ALONG_Y]]), vertices=vertices, faces=faces)
    ball = BodyGroup(shape="sphere", size=(0.045,), names=["a"],
                     poses=np.array([[0.02, 0, 0.8, 0, 0, 0, 1]]))
    engine.spawn([floor(), pin, ball])
    engine.step(200)
    snapshot = engine.snapshot()
    assert_same_runs(engine, restored(snapshot), [steps(300)] * 2)
    broken = copy.deepcopy(snapshot)
    (vertices,) = [v for v in broken["meshes"].values() if v["data"]]
    vertices["data"] = np.full(len(vertices["data"]) // 4, np.nan, dtype="<f4").tobytes()
    with pytest.raises(InvalidArgumentError, match="not finite"):
        MujocoEngine().restore(broken)


def test_a_snapshot_restores_twice_alike_and_after_its_source_closed(
        engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(400)
    snapshot = engine.snapshot()
    engine.step(300)
    expected = state(engine)
    engine.close()
    del engine
    first, second = restored(snapshot), restored(snapshot)
    first.step(300)
    second.step(300)
    np.testing.assert_array_equal(state(first), expected)
    np.testing.assert_array_equal(state(second), expected)


def test_a_snapshot_survives_msgpack(engine: MujocoEngine, rng: np.random.Generator) -> None:
    engine.spawn([floor()])
    pile(engine, rng)
    engine.step(400)
    blob = msgpack.packb(engine.snapshot(), use_bin_type=True)
    assert_same_runs(engine, restored(msgpack.unpackb(blob, raw=False)), [steps(300)])


# -- refusals -------------------------------------------------------------------------------
@pytest.fixture
def snapshot(engine: MujocoEngine, rng: np.random.Generator) -> dict[str, Any]:
    engine.spawn([floor()])
    kuka(engine)
    pile(engine, rng, count=8)
    engine.step(50)
    return engine.snapshot()


def _truncated(snap: dict[str, Any]) -> None:
    qpos = snap["data"]["arrays"]["qpos"]
    qpos["data"] = qpos["data"][:-8]


def _sleep_cycles_broken(snap: dict[str, Any]) -> None:
    asleep = snap["data"]["sleep"]["tree_asleep"]
    asleep["data"] = b"\x7f" * len(asleep["data"])  # every tree names a tree far beyond


def _set(path: str, value: Any) -> Callable[[dict[str, Any]], None]:
    def change(snap: dict[str, Any]) -> None:
        *parents, last = path.split(".")
        node = snap
        for key in parents:
            node = node[key]
        node[last] = value
    return change


@pytest.mark.parametrize(("change", "words"), [
    (_set("engine", "pybullet"), "pybullet"),
    (_set("format", 99), "format 99"),
    (_set("engine_version", "2.0.0"), "MuJoCo '2.0.0'"),
    (_truncated, "qpos must be"),
    (_set("params", [1, 2]), "params"),
    (_set("params.timestep", "fast"), "timestep"),
    (_set("spec", 42), "MJCF text"),
    (_set("spec", "<mujoco><worldbody/></mujoco>"), "compiles to a world"),
    (_set("entities", {"a": 1}), "entities must be a list"),
    (_set("data.arrays.qvel.dtype", "<i4"), "dtype"),
    (_sleep_cycles_broken, "tree_asleep"),
    (_set("targets", {"k/J0": ["position", 1.0, "two", 0.0, 1.0]}), "numbers"),
    (_set("targets", {"k/lbr_iiwa_joint_1": ["position", 1.0, math.nan, 0.0, 1.0]}),
     "finite numbers"),
    (_set("wrenches", {"nobody": None}), "nobody"),
    (lambda s: s.pop("pool"), "missing ['pool']"),
    (lambda s: s["bodies"].reverse(), "another order"),
    (_set("bodies", "all"), "another order"),
    (_set("meshes", {}), "meshes"),
], ids=["other-engine", "format", "version", "truncated", "params-type", "param-value",
        "spec-type", "other-world", "entities-type", "dtype", "sleep-cycles", "target-type",
        "target-nan", "wrench-name", "missing-key", "body-order",
        "body-order-type", "meshes-missing"])
def test_a_malformed_snapshot_is_refused_with_a_typed_error(
        snapshot: dict[str, Any], change: Callable[[dict[str, Any]], None],
        words: str) -> None:
    bad = copy.deepcopy(snapshot)
    change(bad)
    with pytest.raises(InvalidArgumentError, match=words.replace("[", r"\[").replace(
            "]", r"\]")):
        MujocoEngine().restore(bad)


def _leaves(node: Any, path: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Paths to every value of a snapshot that is no map or list."""
    if isinstance(node, dict):
        return [p for k, v in node.items() for p in _leaves(v, (*path, k))]
    if isinstance(node, list):
        return [p for i, v in enumerate(node) for p in _leaves(v, (*path, i))]
    return [path]


MANGLED = [None, -1, 2**40, 1e308, "x", b"\x00" * 3, [], {}, True]


def test_a_mangled_snapshot_restores_or_is_refused_with_a_typed_error(
        snapshot: dict[str, Any]) -> None:
    """Any one value replaced by something else: a world that steps, or InvalidArgumentError
    (never a crash or another error); seeded."""
    rng = np.random.default_rng(SEED)
    leaves = _leaves(snapshot)
    for pick in rng.choice(len(leaves), size=120, replace=False):
        bad = copy.deepcopy(snapshot)
        *parents, last = leaves[int(pick)]
        node = bad
        for key in parents:
            node = node[key]
        node[last] = MANGLED[int(rng.integers(len(MANGLED)))]
        with contextlib.suppress(InvalidArgumentError):
            engine = MujocoEngine()
            engine.restore(bad)
            engine.step(2)  # a world it accepted also runs


def test_a_target_without_an_effort_limit_restores(snapshot: dict[str, Any]) -> None:
    """max_effort inf means "no limit": a snapshot holding one restores, mode kept."""
    held = copy.deepcopy(snapshot)
    held["targets"] = {"k/lbr_iiwa_joint_1": ["position", 0.2, 100.0, 10.0, math.inf]}
    restored_engine = MujocoEngine()
    restored_engine.restore(held)
    modes = {j.name: j.mode for j in restored_engine.joints()}
    assert modes["k/lbr_iiwa_joint_1"] == "position"


def test_a_restored_model_world_compiles_again_without_a_deprecation_warning(
        engine: MujocoEngine, caplog: pytest.LogCaptureFixture) -> None:
    """A loaded model's world restored, then edited (a recompile), logs no MuJoCo warning:
    restoring once carried the model's meaninertia into the spec, and every later compile
    logged MuJoCo's deprecation of it (issue 47)."""
    engine.spawn([floor()])
    kuka(engine)
    engine.step(5)
    copy = restored(engine.snapshot())
    with caplog.at_level("WARNING"):
        copy.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["late"],
                              poses=np.array([[0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 1.0]]))])
    assert not [r for r in caplog.records if "MuJoCo" in r.getMessage()], caplog.text
