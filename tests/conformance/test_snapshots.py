"""Snapshots through real daemons, the same on every engine: after a restore the same steps
give the same states bit for bit (contacts; a KUKA with targets and a wrench), however often
it is restored; a restore brings back a scene changed since; a blob restores in another
daemon; bad input is refused with the world unchanged; slot limits hold."""

from __future__ import annotations

import hashlib
from collections.abc import Iterator

import msgpack
import numpy as np
import pytest
from support import snapshot
from support.models import KUKA_JOINTS, KUKA_KD, KUKA_KP, load_robot, model_snapshot
from support.worlds import clean, contact_scene

from galton.client import (
    Client,
    EmbeddedDaemon,
    InvalidArgumentError,
    NotFoundError,
    ResourceLimitError,
    spheres,
    wait_for_daemon,
)
from galton.client.fuzz.extremes import ARM
from galton.client.fuzz.snapshots import open_blob, reseal

STEPS = 150
OTHER_ENGINE = {"mujoco": "pybullet", "pybullet": "mujoco", "ode": "mujoco", "dart": "mujoco"}
DEFAULT_MAX_SNAPSHOTS = 16  # docs/protocol.md, "Limits"


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        yield client


def run(sim: Client, names: list[str], count: int = STEPS) -> np.ndarray:
    """``count`` steps; every named body's pose and twist after each of three chunks."""
    chunks = [sim.step_and_read(count // 3, names) for _ in range(3)]
    return np.concatenate([np.hstack([c.poses, c.twists]).ravel() for c in chunks])


def drive_kuka(sim: Client) -> np.ndarray:
    """Position targets on four joints, efforts on three, a wrench on the last link; the
    joints' and links' states after each of three chunks of steps."""
    sim.set_joint_targets(KUKA_JOINTS[:4], "position", [0.4, -0.3, 0.2, 0.5],
                          kp=KUKA_KP[:4], kd=KUKA_KD[:4])
    out = []
    for _ in range(3):
        states, joints = sim.step_and_read_both(40, ["lbr_iiwa_link_7"], KUKA_JOINTS)
        out += [states.poses.ravel(), states.twists.ravel(), joints.positions,
                joints.velocities, joints.efforts]
    return np.concatenate(out)


def test_the_same_steps_after_a_restore_give_the_same_states(world: Client) -> None:
    names = contact_scene(world)
    world.step(20)
    world.snapshot("start")
    first = run(world, names)
    world.restore("start")
    again = run(world, names)
    world.restore("start")
    twice = run(world, names)
    np.testing.assert_array_equal(again, twice)  # however often it is restored
    np.testing.assert_array_equal(first, again)  # and as the source went on


def test_a_kuka_with_targets_and_a_wrench_replays_bit_for_bit(world: Client) -> None:
    load_robot(world, "kuka")
    world.set_joint_states(KUKA_JOINTS, np.linspace(-0.5, 0.5, 7), 0.1)
    world.set_joint_targets(KUKA_JOINTS[4:], "effort", [0.5, -0.5, 0.2])
    world.apply_wrench(["lbr_iiwa_link_7"], [5, 0, 0, 0, 0, 0.3])
    world.step(30)
    taken = world.snapshot(blob=True)
    assert taken.blob is not None and taken.slot is None
    first = drive_kuka(world)
    world.restore(blob=taken.blob)
    again = drive_kuka(world)
    world.restore(blob=taken.blob)
    np.testing.assert_array_equal(again, drive_kuka(world))
    np.testing.assert_array_equal(first, again)


def test_a_kuka_slot_replays_bit_for_bit_after_its_targets_changed(world: Client) -> None:
    """A slot kept as a state (no rebuild) brings back the targets and the model numbers
    they write, as a blob does."""
    load_robot(world, "kuka")
    world.set_joint_targets(KUKA_JOINTS[4:], "effort", [0.5, -0.5, 0.2])
    world.step(30)
    world.snapshot("arm")
    first = drive_kuka(world)
    world.restore("arm")
    np.testing.assert_array_equal(first, drive_kuka(world))


def test_a_slot_replays_bit_for_bit_after_the_structure_changed(world: Client) -> None:
    """After a spawn and a delete (another structure), a slot restores through the portable
    path and still goes on as the source went on."""
    names = contact_scene(world)
    world.step(20)
    world.snapshot("start")
    first = run(world, names)
    world.spawn(spheres(["late"], [[1, 1, 1]], 0.1))
    world.delete(["late"])
    world.restore("start")
    np.testing.assert_array_equal(first, run(world, names))
    world.restore("start")  # and again in place
    np.testing.assert_array_equal(first, run(world, names))


def test_a_restore_brings_back_a_scene_changed_since(world: Client) -> None:
    names = contact_scene(world)
    load_robot(world, "kuka", prefix="arm_")
    world.step(10)
    before = model_snapshot(world)
    world.snapshot("before")
    world.spawn(spheres(["late"], [[1, 1, 1]], 0.1))
    world.delete(names[:2])
    world.delete(["arm_lbr_iiwa_link_0"])
    world.step(25)
    row = world.restore("before")
    assert (row.step, row.entity_count) == (10, len(before.scene.entities))
    model_snapshot(world).assert_same(before)


def test_a_blob_restores_in_another_daemon_of_the_same_engine(world: Client,
                                                              engine: str) -> None:
    names = contact_scene(world)
    world.step(15)
    blob = world.snapshot(blob=True).blob
    assert blob is not None
    other = EmbeddedDaemon(engine, instance=f"test-{engine}-other").start(60.0)
    try:
        with Client(other.instance, other.endpoint, timeout=20.0) as there:
            wait_for_daemon(there.session, other.instance, 60.0)
            row = there.restore(blob=blob)
            assert (row.step, row.engine) == (15, engine)
            assert snapshot(there).entities == snapshot(world).entities
            np.testing.assert_array_equal(run(there, names), run(world, names))
    finally:
        other.stop()


def test_an_unknown_slot_or_world_is_not_found(world: Client) -> None:
    contact_scene(world)
    world.snapshot("kept")
    before = snapshot(world)
    with pytest.raises(NotFoundError, match="kept"):
        world.restore("kep")
    with pytest.raises(NotFoundError):
        world.delete_snapshot("nothing")
    with pytest.raises(NotFoundError):
        world.world("nowhere").snapshot("s")
    with pytest.raises(NotFoundError):
        world.world("nowhere").restore("kept")
    before.assert_same(snapshot(world))


def not_a_snapshot(blob: bytes) -> list[bytes]:
    """Blobs a daemon must refuse: cut short, a byte flipped at its start or deep inside a
    number (the digest catches it), msgpack that is no snapshot, another format outside or
    inside (with a digest that matches)."""
    outer = msgpack.unpackb(blob, raw=False)
    flipped, deep = bytearray(blob), bytearray(blob)
    flipped[0] ^= 0xFF
    deep[len(deep) * 3 // 4] ^= 0x01
    inner = msgpack.unpackb(outer["body"], raw=False)
    body = msgpack.packb({**inner, "format": 999}, use_bin_type=True)
    renumbered_inside = {**outer, "body": body,
                         "blake2b": hashlib.blake2b(body, digest_size=32).digest()}
    return [blob[: len(blob) // 2], bytes(flipped), bytes(deep), b"\x00not msgpack",
            msgpack.packb({"engine": "nothing"}), msgpack.packb([1, 2, 3]),
            msgpack.packb({**outer, "galton_snapshot": 999}, use_bin_type=True),
            msgpack.packb(renumbered_inside, use_bin_type=True)]


def test_a_blob_of_the_other_engine_or_a_broken_one_changes_nothing(world: Client,
                                                                    engine: str) -> None:
    other = world.create_world("elsewhere", engine=OTHER_ENGINE[engine])
    assert other.engine == OTHER_ENGINE[engine]
    there = world.world("elsewhere")
    contact_scene(there)
    foreign = there.snapshot(blob=True).blob
    assert foreign is not None
    contact_scene(world)
    world.step(5)
    own = world.snapshot(blob=True).blob
    assert own is not None
    before = snapshot(world)
    for blob in [foreign, *not_a_snapshot(own)]:
        with pytest.raises(InvalidArgumentError):
            world.restore(blob=blob)
        before.assert_same(snapshot(world))


def test_restore_takes_exactly_one_of_slot_or_blob(world: Client) -> None:
    with pytest.raises(InvalidArgumentError):
        world.call("restore", {})
    with pytest.raises(InvalidArgumentError):
        world.call("restore", {"slot": "a", "blob": b"x"})
    with pytest.raises(InvalidArgumentError):
        world.call("snapshot", {})


def test_slots_past_the_limit_are_refused_and_nothing_is_kept(world: Client) -> None:
    world.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    for i in range(DEFAULT_MAX_SNAPSHOTS):
        world.snapshot(f"slot_{i}")
    with pytest.raises(ResourceLimitError) as refused:
        world.snapshot("one_more")
    assert refused.value.details["limit"] == "max_snapshots"
    assert len(world.snapshots()) == DEFAULT_MAX_SNAPSHOTS
    world.snapshot("slot_0")  # replacing a slot is no new slot
    assert {s.slot for s in world.snapshots()} == {f"slot_{i}" for i in range(16)}
    world.delete_snapshot("slot_3")
    world.snapshot("one_more")


def test_snapshots_lists_what_each_slot_holds(world: Client, engine: str) -> None:
    names = contact_scene(world)
    world.step(7)
    taken = world.snapshot("seven", blob=True)
    assert taken.blob is not None and taken.nbytes == len(taken.blob)
    (row,) = world.snapshots()
    assert (row.slot, row.world, row.engine, row.step, row.entity_count) == (
        "seven", "default", engine, 7, len(names) + 1)
    assert row.nbytes == taken.nbytes and row.blob is None


def test_slot_bytes_past_the_limit_are_refused(world: Client, engine: str) -> None:
    """A daemon whose max_snapshot_bytes holds three and a half snapshots of a scene keeps
    three and refuses the fourth, keeping nothing of it."""
    contact_scene(world)
    size = world.snapshot("probe").nbytes  # a slot's bytes: its blob, or its kept state
    blob_size = world.snapshot(blob=True).nbytes
    limit = int(3.5 * size)
    with EmbeddedDaemon(engine, instance=f"test-{engine}-slots",
                        extra_args=["--limit", f"max_snapshot_bytes={limit}"]) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
        wait_for_daemon(sim.session, daemon.instance, 60.0)
        contact_scene(sim)
        for i in range(3):
            sim.snapshot(f"slot_{i}")
        with pytest.raises(ResourceLimitError) as refused:
            sim.snapshot("one_more")
        assert refused.value.details["limit"] == "max_snapshot_bytes"
        assert [s.slot for s in sim.snapshots()] == ["slot_0", "slot_1", "slot_2"]
        assert sim.snapshot(blob=True).nbytes == blob_size  # a blob alone is kept nowhere


def test_a_hostile_resealed_blob_is_a_typed_refusal(world: Client) -> None:
    """Issue 46: a re-sealed body whose link names were lists or maps reached Python's own
    TypeError (OPERATION_FAILED, raw) on DART; every such body is INVALID_ARGUMENT, and the
    world stays as it was."""
    world.spawn(spheres(["a", "b"], [[0, 0, 1], [0.2, 0, 1]], 0.05))
    world.call("load_model", {"format": "urdf", "text": ARM, "prefix": "x_"})
    world.step(5)
    own = world.snapshot(blob=True).blob
    assert own is not None
    body = open_blob(own)
    links = [i for i, e in enumerate(body["entities"]) if e.get("shape") == "link"]
    before = snapshot(world)
    for index in links[:2]:
        for key in ("name", "model"):
            for odd in ([], {}):
                edited = open_blob(own)
                edited["entities"][index][key] = odd
                with pytest.raises(InvalidArgumentError):
                    world.restore(blob=reseal(edited))
                before.assert_same(snapshot(world))
