"""The SDK's worlds against real daemons: a world view's requests name its world and share
its client's life, values built from replies (shapes of a prediction, a snapshot's blob),
client-side refusals, and lockstep with an external clock (drift 0 over 60 s at 100 Hz)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.worlds import clean

from galton.client import (
    Client,
    ClientClosedError,
    InvalidArgumentError,
    NotFoundError,
    Prediction,
    SnapshotInfo,
    WorldInfo,
    lockstep,
    plane,
    spheres,
)

CLOCK_HZ = 100.0
CLOCK_SECONDS = 60.0


@pytest.fixture
def world(sim: Client) -> Iterator[Client]:
    with clean(sim) as client:
        yield client


def test_a_world_view_names_its_world_in_every_request(world: Client) -> None:
    world.create_world("side")
    side = world.world("side")
    assert (side.world_name, world.world_name) == ("side", None)
    side.spawn(spheres(["ball"], [[0, 0, 1]], 0.05))
    side.step(3)
    assert [e.name for e in side.list()] == ["ball"] and world.list() == []
    assert side.status().step == 3 and world.status().step == 0
    assert side.call("list_worlds")["worlds"][0]["name"] == "default"
    assert side.world("default").status().step == 0  # a view of a view


def test_a_view_shares_its_client_life(world: Client) -> None:
    world.create_world("side")
    parent = Client(world.instance, session=world.session)
    side = parent.world("side")
    side.close()
    assert side.closed and not parent.closed
    assert parent.status().engine
    again = parent.world("side")
    parent.close()
    assert again.closed
    with pytest.raises(ClientClosedError):
        again.status()
    with pytest.raises(ClientClosedError):
        parent.world("side")
    assert world.status().engine  # the shared session stays open


def test_a_world_view_needs_a_name(world: Client) -> None:
    with pytest.raises(InvalidArgumentError):
        world.world("")
    with pytest.raises(NotFoundError):
        world.world("nowhere").list()


def test_values_are_built_from_their_replies(world: Client, engine: str) -> None:
    world.spawn(plane())
    world.spawn(spheres(["a", "b"], [[0, 0, 1], [1, 0, 1]], 0.05))
    taken = world.snapshot("s", blob=True)
    assert isinstance(taken, SnapshotInfo) and taken.blob is not None
    assert (taken.slot, taken.world, taken.engine, taken.nbytes) == (
        "s", "default", engine, len(taken.blob))
    assert world.snapshot(blob=True).slot is None
    assert world.snapshot("t").blob is None
    dt = world.status().timestep
    found = world.predict(9 * dt, every=3 * dt, read=["b", "a"])
    assert isinstance(found, Prediction) and len(found) == 4
    assert found.names == ["b", "a"] and found.poses.shape == (4, 2, 7)
    assert found.joint_positions.shape == (4, 0)
    np.testing.assert_array_equal(found.at("a"), found.poses[:, 1])
    np.testing.assert_allclose(found.times, np.arange(4) * 3 * dt, atol=1e-12)
    assert found.poses[-1, 1, 2] < 1.0  # it fell
    row = world.restore(blob=taken.blob)
    assert isinstance(row, WorldInfo) and row.live and row.name == "default"


def test_restore_takes_exactly_one_source_before_any_request(world: Client) -> None:
    with pytest.raises(InvalidArgumentError, match="exactly one"):
        world.restore()
    with pytest.raises(InvalidArgumentError, match="exactly one"):
        world.restore("s", b"x")


def test_lockstep_keeps_the_world_at_the_clock_stamps(world: Client) -> None:
    """A robot's clock at 100 Hz for 60 s: after each stamp the world's sim time is that
    stamp (the timestep divides 10 ms), so the drift is 0 over the whole run."""
    world.set_params({"timestep": 0.002})
    world.spawn(plane())
    world.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05))
    stamps = np.arange(1, int(CLOCK_SECONDS * CLOCK_HZ) + 1) / CLOCK_HZ
    reached = list(lockstep(world, stamps))
    steps = np.array([r.step for r in reached])
    times = np.array([r.sim_time for r in reached])
    np.testing.assert_array_equal(steps, np.arange(1, len(stamps) + 1) * 5)
    assert np.max(np.abs(times - stamps)) < 1e-9
    assert world.status().sim_time == pytest.approx(CLOCK_SECONDS, abs=1e-9)


def test_lockstep_takes_no_step_for_a_stamp_already_reached(world: Client) -> None:
    world.set_params({"timestep": 0.002})
    world.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05))
    reached = list(lockstep(world, [0.0, 0.003, 0.004, 0.0041, 0.006]))
    assert [r.step for r in reached] == [0, 2, 2, 3, 3]
