"""PyBullet snapshots, in-process: a world taken as plain data and restored into a fresh
engine goes on bit for bit as the world it was taken from (which the snapshot rebuilt),
survives msgpack and the source's closing, restores any number of times, and a
malformed or foreign snapshot is refused with a typed error."""

from __future__ import annotations

import copy
from collections.abc import Callable, Iterator
from typing import Any

import msgpack
import numpy as np
import pytest
from support.models import KUKA_JOINTS, KUKA_KD, KUKA_KP
from support.pybullet_worlds import (
    MJCF,
    SEED,
    assert_same_run,
    kuka_text,
    names_of,
    now,
    pile,
    poses_at,
    record,
    restored,
)

from galton.daemon.engines.base import FEATURE_SNAPSHOT
from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.daemon.engines.pybullet.snapshot.arrays import pack
from galton.protocol import BodyGroup, BodyProperties, InvalidArgumentError


@pytest.fixture
def engines() -> Iterator[Callable[[], PybulletEngine]]:
    """Fresh engines, all closed at the end."""
    made: list[PybulletEngine] = []

    def make() -> PybulletEngine:
        made.append(PybulletEngine())
        return made[-1]
    yield make
    for engine in made:
        engine.close()


def assert_continues_alike(make: Callable[[], PybulletEngine], source: PybulletEngine,
                           steps: int = 400,
                           between: Callable[[PybulletEngine, int], None] | None = None
                           ) -> dict[str, Any]:
    """Snapshot ``source``, restore it into a fresh engine, and check that both read the
    same states now and after the same steps and requests."""
    names = names_of(source)
    before = now(source, names)
    data = source.snapshot()
    assert now(source, names) == before  # rebuilt, and reads as it did
    copy_ = restored(make, data)
    assert names_of(copy_) == names
    assert now(copy_, names) == before
    assert copy_.get_params() == source.get_params()
    assert copy_.joints() == source.joints()
    assert_same_run(record(source, names, steps, between=between),
                    record(copy_, names, steps, between=between))
    return data


# -- the promise: bit for bit from the snapshot on -------------------------------------------
def test_a_pile_in_contact_goes_on_alike(engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.spawn(pile(np.random.default_rng(SEED)))
    source.step(150)  # landed in one another: contacts with warm starts to forget
    assert_continues_alike(engines, source)
    assert FEATURE_SNAPSHOT in source.capabilities().features


def test_a_kuka_with_targets_and_a_wrench_goes_on_alike(
        engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.set_params({"timestep": 0.002})
    source.load_model("urdf", kuka_text(), None, "k/")
    source.spawn([BodyGroup("sphere", (0.05,), [f"ball{i}" for i in range(5)],
                            poses_at([[0.1 * i - 0.2, 0.1, 1.5] for i in range(5)]))])
    joints = ["k/" + j for j in KUKA_JOINTS]
    n = len(joints)
    source.set_joint_targets(joints, "position", np.full(n, 0.4), KUKA_KP, KUKA_KD,
                             np.full(n, np.inf))
    source.set_wrenches(["k/lbr_iiwa_link_7", "ball0"], np.array(
        [[0, 5.0, 0, 0, 0, 0.5], [1.0, 0, 0, 0, 0, 0]]), None)
    source.update(["k/lbr_iiwa_link_0"], BodyProperties(friction=0.7))
    source.step(300)

    def requests(engine: PybulletEngine, k: int) -> None:
        if k == 3:
            engine.set_joint_targets(joints[:2], "velocity", np.array([0.5, -0.5]),
                                     np.zeros(2), np.array([20.0, 30.0]), np.full(2, 50.0))
        if k == 6:
            engine.clear_wrenches(["ball0"])
            engine.set_joint_states([joints[3]], np.array([0.2]), None)

    data = assert_continues_alike(engines, source, between=requests)
    kinds = [run["kind"] for run in data["runs"]]
    assert kinds == ["model", "spawn"] and data["models"][0]["active"]


def test_spawn_delete_and_update_churn_goes_on_alike(
        engines: Callable[[], PybulletEngine]) -> None:
    """Holes left by deletes, groups partly gone, bodies updated, defaults changed."""
    rng = np.random.default_rng(SEED)
    source = engines()
    source.spawn(pile(rng))
    source.step(60)
    source.delete(["s3", "b0", "b5", "s7"])
    source.spawn(pile(rng, "late/", 5))
    source.update(["s1", "late/b2"], BodyProperties(mass=0.5, restitution=0.3,
                                                    rgba=(1, 0, 0, 1)))
    source.set_params({"default_friction": 0.7, "pybullet.collision_margin": 0.002})
    source.delete(["late/ground", "late/s0"])
    source.step(40)
    source.set_states(["s2"], poses_at([[0, 0, 0.6]], [0.3]), None)  # given, not stepped
    assert_continues_alike(engines, source)


def test_an_mjcf_load_partly_deleted_goes_on_alike(
        engines: Callable[[], PybulletEngine]) -> None:
    """Several bodies from one load, one of them deleted, one updated, all in contact."""
    source = engines()
    infos = source.load_model("mjcf", MJCF, None, "m/")
    roots = [info.name for info in infos if info.shape == "model"]
    source.step(100)
    source.delete([roots[2]])
    source.update([roots[3]], BodyProperties(mass=2.0, friction=0.9))
    source.step(30)
    data = assert_continues_alike(engines, source)
    assert data["runs"][0]["index"] == [0, 1, 3]


def test_parameter_changes_after_the_restore_go_on_alike(
        engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.set_params({"gravity": [0.5, 0.0, -9.0], "solver_iterations": 20})
    source.spawn(pile(np.random.default_rng(SEED)))
    source.step(100)

    def requests(engine: PybulletEngine, k: int) -> None:
        if k == 2:
            engine.set_params({"pybullet.contact_erp": 0.2, "default_restitution": 0.5,
                               "timestep": 1 / 480})
    data = assert_continues_alike(engines, source, between=requests)
    assert data["params"]["gravity"] == [0.5, 0.0, -9.0]


def test_the_source_goes_on_as_after_reset_dynamics(
        engines: Callable[[], PybulletEngine]) -> None:
    """What a snapshot costs its world: the contact history, exactly as a rewind does."""
    rng = np.random.default_rng(SEED)
    groups = pile(rng)
    taken, rewound = engines(), engines()
    for engine in (taken, rewound):
        engine.spawn(copy.deepcopy(groups))
        engine.step(150)
    names = names_of(taken)
    taken.snapshot()
    rewound.reset_dynamics()
    assert_same_run(record(taken, names, 200), record(rewound, names, 200))


def test_a_snapshot_that_is_not_canonical_leaves_its_source_alone(
        engines: Callable[[], PybulletEngine]) -> None:
    """The source goes on as an untouched twin; the restore as a rewound twin."""
    groups = pile(np.random.default_rng(SEED))
    source, twin, rewound = engines(), engines(), engines()
    for engine in (source, twin, rewound):
        engine.spawn(copy.deepcopy(groups))
        engine.step(150)
    names = names_of(source)
    copy_ = restored(engines, source.snapshot(canonical=False))
    rewound.reset_dynamics()
    assert_same_run(record(source, names, 200), record(twin, names, 200))
    assert_same_run(record(copy_, names, 200), record(rewound, names, 200))


# -- restoring: many times, after the source is gone, through msgpack ------------------------
def test_a_snapshot_restores_many_times_and_outlives_its_source(
        engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.load_model("urdf", kuka_text(), None, "k/", fixed_base=False)
    source.spawn(pile(np.random.default_rng(SEED)))
    source.step(100)
    names = names_of(source)
    data = source.snapshot()
    expected = record(source, names, 200)
    source.close()
    blob = msgpack.packb(data, use_bin_type=True)
    runs = [record(restored(engines, msgpack.unpackb(blob, raw=False)), names, 200)
            for _ in range(2)]
    assert_same_run(runs[0], expected)
    assert_same_run(runs[1], expected)


def test_a_restored_engine_does_everything_else(engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.spawn(pile(np.random.default_rng(SEED)))
    source.load_model("urdf", kuka_text(), None, "k/")
    engine = restored(engines, source.snapshot())
    engine.spawn([BodyGroup("sphere", (0.03,), ["new"], poses_at([[1, 1, 1]]))])
    engine.delete(["s0", "b1"])
    engine.set_joint_states(["k/lbr_iiwa_joint_2"], np.array([0.3]), np.array([0.0]))
    engine.step(20)
    engine.reset_dynamics()
    assert repr(engine._batches) == "count(5)"  # groups 0-2, the KUKA 3, "new" 4
    assert "new" in engine.snapshot()["runs"][-1]["names"]
    engine.clear()
    assert not engine.bodies and not engine.joints()


def test_an_empty_world_keeps_its_parameters(engines: Callable[[], PybulletEngine]) -> None:
    source = engines()
    source.set_params({"timestep": 0.01})
    data = source.snapshot()
    assert data["runs"] == [] and restored(engines, data).timestep == 0.01


# -- refusals: the snapshot is untrusted input ------------------------------------------------
def cut(data: dict[str, Any], path: tuple[Any, ...], value: Any) -> dict[str, Any]:
    """A deep copy of ``data`` with the field at ``path`` replaced (deleted: ``...``;
    one past a list's end: appended)."""
    out = copy.deepcopy(data)
    place = out
    for key in path[:-1]:
        place = place[key]
    if value is ...:
        del place[path[-1]]
    elif isinstance(place, list) and path[-1] == len(place):
        place.append(value)
    else:
        place[path[-1]] = value
    return out


BROKEN = {
    "another engine's": (("engine",), "mujoco", "mujoco"),
    "another format": (("format",), 2, "format 2"),
    "no parameters": (("params",), ..., "missing field 'params'"),
    "a parameter of mujoco": (("params", "mujoco.solref"), [0.02, 1], "unknown field"),
    "a truncated array": (("poses", "data"), b"\0" * 100, "holds 100 bytes"),
    "a wrong shape": (("twists", "shape"), [3, 6], "has shape"),
    "names that are not a list": (("runs", 1, "names"), "s0", "must be list"),
    "a number as text": (("runs", 1, "made_mass"), "1.0", "must be int or float"),
    "an array that is none": (("runs", 2, "mass"), None, "must be dict"),
    "a negative mass": (("runs", 2, "mass"), pack([-1.0, 1, 1]), "mass is out of range"),
    "a NaN colour": (("runs", 2, "rgba"), pack(np.full((3, 4), 2.0)), "outside"),
    "an unknown shape": (("runs", 1, "shape"), "torus", "torus"),
    "a name used twice": (("runs", 3, "names", 0), "s1", "used twice"),
    "a model text that is no model": (("runs", 0, "text"), "<robot>", "cannot be restored"),
    "joints twice": (("models", 0, "indices", 0), 6, "distinct joint indices"),
    "links the model lacks": (("models", 0, "links", 7), "k/extra", "do not fit"),
    "a wrench on nobody": (("wrenches", "names"), ["nobody"], "nobody"),
}


@pytest.mark.parametrize("why", list(BROKEN))
def test_a_broken_snapshot_is_refused(engines: Callable[[], PybulletEngine], why: str) -> None:
    source = engines()
    source.load_model("urdf", kuka_text(), None, "k/")
    source.spawn(pile(np.random.default_rng(SEED), count=3))
    source.set_wrenches(["s0"], np.array([[0, 0, 1.0, 0, 0, 0]]), None)
    path, value, message = BROKEN[why]
    with pytest.raises(InvalidArgumentError, match=message):
        engines().restore(cut(source.snapshot(), path, value))


def test_a_snapshot_is_plain_data() -> None:
    engine = PybulletEngine()
    try:
        engine.spawn(pile(np.random.default_rng(SEED), count=2))
        data = engine.snapshot()
    finally:
        engine.close()
    plain = (dict, list, str, int, float, bool, bytes, type(None))

    def check(value: Any) -> None:
        assert isinstance(value, plain), type(value)
        children = value.values() if isinstance(value, dict) else (
            value if isinstance(value, list) else ())
        assert all(isinstance(key, str) for key in (value if isinstance(value, dict) else ()))
        for child in children:
            check(child)
    check(data)
    assert msgpack.unpackb(msgpack.packb(data, use_bin_type=True), raw=False) == data


def test_mangled_snapshots_give_only_typed_errors(
        engines: Callable[[], PybulletEngine]) -> None:
    """Seeded mutations of every field: a restore succeeds or says InvalidArgumentError."""
    source = engines()
    source.load_model("urdf", kuka_text(), None, "k/")
    source.spawn(pile(np.random.default_rng(SEED), count=2))
    data = source.snapshot()
    places = list(fields_of(data))
    values = [None, -1, 1.5, np.nan, np.inf, "x", b"\0" * 8, [], {}, [1], True, 10**12, "s1"]
    rng = np.random.default_rng(SEED)
    for _ in range(150):
        path = places[rng.integers(len(places))]
        value = values[rng.integers(len(values))]
        engine = PybulletEngine()
        try:
            engine.restore(cut(data, path, value))
            engine.step(2)
        except InvalidArgumentError:
            pass
        finally:
            engine.close()


def fields_of(value: Any, path: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """The path of every field and item below ``value``."""
    items = value.items() if isinstance(value, dict) else (
        enumerate(value) if isinstance(value, list) else ())
    for key, child in items:
        yield (*path, key)
        yield from fields_of(child, (*path, key))
