"""Scene-graph CRUD through a real daemon, the same on every engine."""

from __future__ import annotations

import numpy as np
import pytest
from support import ball_row, snapshot

from galton.client import Client, body_group, plane, spheres
from galton.protocol import BODY_SHAPES, NameNotUniqueError, NotFoundError


def test_capabilities_name_the_engine(sim: Client, engine: str) -> None:
    caps = sim.capabilities()
    assert caps.engine == engine
    assert caps.engine_version
    assert set(caps.body_shapes) == set(BODY_SHAPES)  # every engine takes meshes too
    assert "timestep" in caps.params and "default" in caps.params["timestep"]


@pytest.mark.parametrize("count", [1, 1000], ids=["batch-1", "batch-1000"])
def test_spawn_list_get_delete_round_trip(sim: Client, count: int) -> None:
    names, group = ball_row(count)
    assert sim.spawn(group) == names
    assert sorted(e.name for e in sim.list()) == sorted(names)
    states = sim.get_states(names)
    assert states.names == names
    np.testing.assert_allclose(states.poses, group.poses, atol=1e-9)
    np.testing.assert_allclose(states.twists, 0.0, atol=1e-12)
    sim.delete(names)
    assert sim.list() == []
    assert sim.status().entity_count == 0


@pytest.mark.parametrize("shape, size", [
    ("sphere", (0.1,)), ("box", (0.1, 0.2, 0.3)), ("cylinder", (0.1, 0.2)),
    ("capsule", (0.1, 0.2)),
])
def test_every_shape_spawns_static_and_dynamic(sim: Client, shape: str, size: tuple) -> None:
    sim.spawn(body_group(shape, size, ["moving"], [[0, 0, 2]]),
              body_group(shape, size, ["fixed"], [[1, 0, 2]], static=True))
    sim.step(10)
    moving, fixed = sim.get_states(["moving", "fixed"]).positions
    assert moving[2] < 2.0
    assert fixed[2] == pytest.approx(2.0)


def test_plane_is_static(sim: Client) -> None:
    sim.spawn(plane("floor"))
    [info] = sim.list()
    assert info.static and info.shape == "plane"


def test_stale_name_fails_and_a_deleted_name_may_be_reused(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    sim.delete([names[0]])
    with pytest.raises(NotFoundError, match="ball_0"):
        sim.get_states([names[0]])
    with pytest.raises(NotFoundError):
        sim.delete([names[0]])
    sim.spawn(spheres([names[0]], [[5, 5, 5]], 0.05))
    assert sim.get_states([names[0]]).positions[0].tolist() == [5, 5, 5]


def test_duplicate_name_is_refused_and_changes_nothing(sim: Client) -> None:
    _, group = ball_row(3)
    sim.spawn(group)
    before = snapshot(sim)
    with pytest.raises(NameNotUniqueError, match="ball_1"):
        sim.spawn(spheres(["new", "ball_1"], [[0, 1, 1], [0, 2, 1]], 0.05))
    snapshot(sim).assert_same(before)


def test_unknown_name_suggests_the_closest(sim: Client) -> None:
    sim.spawn(ball_row(1)[1])
    with pytest.raises(NotFoundError, match="did you mean 'ball_0'"):
        sim.get_states(["bal_0"])


def test_list_filters_by_glob_tag_and_kind(sim: Client) -> None:
    sim.spawn(plane("floor", tags=("board",)))
    sim.spawn(ball_row(3, tags=("ball",))[1], ball_row(2, prefix="probe", z=3)[1])
    assert {e.name for e in sim.list(name="probe_*")} == {"probe_0", "probe_1"}
    assert {e.name for e in sim.list(tag="ball")} == {"ball_0", "ball_1", "ball_2"}
    assert [e.name for e in sim.list(kind="static")] == ["floor"]
    assert len(sim.list(kind="dynamic")) == 5


def test_set_states_is_seen_by_the_next_get(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    poses = np.array([[1, 2, 3, 0, 0, 0, 1], [4, 5, 6, 0, 0, np.sin(0.5), np.cos(0.5)]])
    twists = np.array([[0.1, 0.2, 0.3, 0, 0, 0], [0, 0, 0, 0.4, 0.5, 0.6]])
    sim.set_states(names, poses, twists)
    states = sim.get_states(names)
    np.testing.assert_allclose(states.poses, poses, atol=1e-9)
    np.testing.assert_allclose(states.twists, twists, atol=1e-9)


def test_set_only_twists_keeps_poses(sim: Client) -> None:
    names, group = ball_row(1)
    sim.spawn(group)
    sim.set_states(names, twists=np.array([[1.0, 0, 0, 0, 0, 0]]))
    states = sim.get_states(names)
    np.testing.assert_allclose(states.poses, group.poses, atol=1e-9)
    assert states.twists[0, 0] == pytest.approx(1.0)


def test_update_changes_properties(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    sim.update(names, friction=0.3, restitution=0.5, mass=2.0, tags=["hot"])
    infos = {e.name: e for e in sim.list()}
    assert all(infos[n].friction == 0.3 and infos[n].restitution == 0.5 for n in names)
    assert all(infos[n].mass == 2.0 and infos[n].tags == ("hot",) for n in names)
    assert {e.name for e in sim.list(tag="hot")} == set(names)


def test_spawn_keeps_the_running_world_state(sim: Client) -> None:
    names, group = ball_row(1, z=5.0)
    sim.spawn(group)
    sim.step(100)
    before = sim.get_states(names)
    sim.spawn(spheres(["late"], [[3, 3, 3]], 0.05))
    after = sim.get_states(names)
    np.testing.assert_allclose(after.poses, before.poses, atol=1e-12)
    np.testing.assert_allclose(after.twists, before.twists, atol=1e-12)
    assert sim.status().step == 100


def test_delete_keeps_the_others_state(sim: Client) -> None:
    names, group = ball_row(3, z=5.0)
    sim.spawn(group)
    sim.step(100)
    before = sim.get_states(names[1:])
    sim.delete([names[0]])
    after = sim.get_states(names[1:])
    np.testing.assert_allclose(after.poses, before.poses, atol=1e-12)
    np.testing.assert_allclose(after.twists, before.twists, atol=1e-12)
