"""PyBullet clones (``Engine.clone``: forks and predictions), in-process: a clone is the world
``restore(snapshot(canonical=False))`` makes, bit for bit, without the plain data between
them; it leaves its source alone, and what either does afterwards never reaches the other.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator

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
)

from galton.daemon.engines.pybullet.engine import PybulletEngine
from galton.protocol import BodyGroup, BodyProperties

Requests = Callable[[PybulletEngine, int], None]


@pytest.fixture
def engines() -> Iterator[list[PybulletEngine]]:
    """Engines to close at the end, clones among them."""
    made: list[PybulletEngine] = []
    yield made
    for engine in made:
        engine.close()


def fresh(made: list[PybulletEngine]) -> PybulletEngine:
    made.append(PybulletEngine())
    return made[-1]


def assert_clone_is_the_restore(made: list[PybulletEngine], source: PybulletEngine,
                                between: Requests | None = None) -> None:
    """The clone and a restore of a non-canonical snapshot read alike now and along the
    same steps and requests; the source reads as it did."""
    names = names_of(source)
    before = now(source, names)
    twin = source.clone()
    made.append(twin)
    restored = fresh(made)
    restored.restore(source.snapshot(canonical=False))
    assert now(source, names) == before
    assert names_of(twin) == names
    assert now(twin, names) == now(restored, names) == before
    assert twin.get_params() == source.get_params()
    assert twin.joints() == restored.joints() == source.joints()
    assert repr(twin._batches) == repr(restored._batches)
    assert_same_run(record(twin, names, 300, between=between),
                    record(restored, names, 300, between=between))


def kuka_world(made: list[PybulletEngine]) -> PybulletEngine:
    source = fresh(made)
    source.set_params({"timestep": 0.002})
    source.load_model("urdf", kuka_text(), None, "k/")
    source.spawn([BodyGroup("sphere", (0.05,), [f"ball{i}" for i in range(5)],
                            poses_at([[0.1 * i - 0.2, 0.1, 1.5] for i in range(5)]))])
    joints = ["k/" + j for j in KUKA_JOINTS]
    source.set_joint_targets(joints, "position", np.full(len(joints), 0.4), KUKA_KP, KUKA_KD,
                             np.full(len(joints), np.inf))
    source.set_wrenches(["k/lbr_iiwa_link_7", "ball0"], np.array(
        [[0, 5.0, 0, 0, 0, 0.5], [1.0, 0, 0, 0, 0, 0]]), None)
    source.update(["k/lbr_iiwa_link_0"], BodyProperties(friction=0.7))
    source.step(300)
    return source


def retarget(engine: PybulletEngine, k: int) -> None:
    """Requests on the KUKA world between batches of steps."""
    joints = ["k/" + j for j in KUKA_JOINTS]
    if k == 3:
        engine.set_joint_targets(joints[:2], "velocity", np.array([0.5, -0.5]), np.zeros(2),
                                 np.array([20.0, 30.0]), np.full(2, 50.0))
    if k == 6:
        engine.clear_wrenches(["ball0"])
        engine.update(["k/lbr_iiwa_link_0"], BodyProperties(friction=0.5, restitution=0.2))
        engine.set_joint_states([joints[3]], np.array([0.2]), None)


def test_a_pile_in_contact_clones_as_it_restores(engines: list[PybulletEngine]) -> None:
    source = fresh(engines)
    source.spawn(pile(np.random.default_rng(SEED)))
    source.step(150)
    assert_clone_is_the_restore(engines, source)


def test_a_kuka_with_targets_a_wrench_and_edits_clones_as_it_restores(
        engines: list[PybulletEngine]) -> None:
    assert_clone_is_the_restore(engines, kuka_world(engines), retarget)


def test_churn_and_a_partly_deleted_mjcf_load_clone_as_they_restore(
        engines: list[PybulletEngine]) -> None:
    """Holes left by deletes, groups partly gone, bodies updated, defaults changed, a pose
    given and not stepped, a load of several models one of them deleted."""
    rng = np.random.default_rng(SEED)
    source = fresh(engines)
    source.spawn(pile(rng))
    roots = [i.name for i in source.load_model("mjcf", MJCF, None, "m/") if i.shape == "model"]
    source.step(60)
    source.delete(["s3", "b0", "b5", roots[2]])
    source.spawn(pile(rng, "late/", 5))
    source.update(["s1", "late/b2", roots[3]], BodyProperties(mass=0.5, restitution=0.3))
    source.set_params({"default_friction": 0.7, "pybullet.collision_margin": 0.002})
    source.step(40)
    source.set_states(["s2"], poses_at([[0, 0, 0.6]], [0.3]), None)

    def requests(engine: PybulletEngine, k: int) -> None:
        if k == 4:
            engine.set_params({"gravity": [0.5, 0.0, -9.0], "default_restitution": 0.5})
            engine.spawn([BodyGroup("sphere", (0.03,), ["new"], poses_at([[0, 0, 0.8]]))])
            engine.update(["s4"], BodyProperties(mass=0.9))
    assert_clone_is_the_restore(engines, source, requests)


def test_what_a_clone_does_never_reaches_its_source_and_the_other_way_round(
        engines: list[PybulletEngine]) -> None:
    """Each goes on as an untouched twin would while the others are changed all over
    (models' records, targets, wrenches, bodies, parameters)."""
    source, untouched = kuka_world(engines), kuka_world(engines)
    names = names_of(source)
    clone, witness, reference = source.clone(), source.clone(), untouched.clone()
    engines.extend([clone, witness, reference])
    meddle(clone)
    for engine in (source, untouched):  # a rebuild reads the models' records too
        engine.reset_dynamics()
    assert now(source, names) == now(untouched, names)
    assert_same_run(record(source, names, 200), record(untouched, names, 200))
    meddle(source)
    for engine in (witness, reference):
        engine.reset_dynamics()
    assert now(witness, names) == now(reference, names)
    assert_same_run(record(witness, names, 200), record(reference, names, 200))


def meddle(engine: PybulletEngine) -> None:
    """Change a KUKA world all over, stepping between the changes."""
    retarget(engine, 3)
    retarget(engine, 6)
    engine.update(["k/lbr_iiwa_link_0", "ball1"], BodyProperties(friction=0.1))
    engine.update(["ball1"], BodyProperties(mass=9.0))
    engine.set_wrenches(["ball2"], np.array([[0, 0, 30.0, 0, 0, 0]]), None)
    engine.step(100)
    engine.delete(["ball3"])
    engine.set_params({"gravity": [0.0, 1.0, -3.0]})
    engine.reset_dynamics()
    engine.step(50)
    engine.restore_joints()
    engine.clear()
    engine.spawn(pile(np.random.default_rng(SEED)))
    engine.step(50)
