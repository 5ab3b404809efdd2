"""Every reply is bounded by ``max_reply_bytes`` (issue 35, item 6): a raw render, a raycast,
a snapshot blob, a mesh's triangles and the reads of a request that steps or sets joints
over it are refused up front (a refused snapshot keeps no slot, a refused step takes none); any
other reply over it (states of many bodies) is refused once encoded, never sent; the daemon
keeps serving and small replies pass. One MuJoCo daemon with a 200 kB limit, over Zenoh and
over ZeroMQ (the limit is the daemon's, the same for every engine)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.models import joints, load_robot

from galton.client import Client, EmbeddedDaemon, camera, meshes, spheres
from galton.daemon.core.reply_limit import reads_size
from galton.protocol import ResourceLimitError, pack_f64
from galton.protocol.envelope import Reply, ResultCode, encode_reply

LIMIT = 200_000
BALLS = 2_000  # their states: 2,000 x 13 float64 and the names, over LIMIT


@pytest.fixture(scope="module")
def bounded() -> Iterator[EmbeddedDaemon]:
    daemon = EmbeddedDaemon("mujoco", instance="reply-limit", zmq=True,
                            extra_args=["--limit", f"max_reply_bytes={LIMIT}"]).start()
    yield daemon
    daemon.stop()


@pytest.fixture(params=["zenoh", "zmq"])
def sim(bounded: EmbeddedDaemon, request: pytest.FixtureRequest) -> Iterator[Client]:
    endpoint = bounded.endpoint if request.param == "zenoh" else bounded.zmq_endpoint
    with Client(bounded.instance, endpoint, timeout=30.0) as client:
        client.load_world("mujoco")
        yield client


def _refused(error: pytest.ExceptionInfo[ResourceLimitError]) -> None:
    assert error.value.details["limit"] == "max_reply_bytes"
    assert error.value.details["max"] == LIMIT
    assert error.value.details["size"] > LIMIT


def test_a_raw_render_and_a_raycast_over_the_limit_are_refused_up_front(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[0, 0, 0.5]], 0.05, static=True))
    big = camera((0, -2, 1), (0, 0, 0), size=(300, 300), outputs=["rgb", "depth"])
    with pytest.raises(ResourceLimitError, match="max_reply_bytes") as refused:
        sim.render(big)
    _refused(refused)
    rays = np.tile([0.0, 0.0, 2.0], (10_000, 1))
    with pytest.raises(ResourceLimitError, match="max_reply_bytes") as refused:
        sim.raycast(rays, np.tile([0.0, 0.0, -1.0], (10_000, 1)))
    _refused(refused)
    assert sim.raycast([[0, 0, 2]], [[0, 0, -1]]).entities == ["ball"]


def test_a_snapshot_blob_over_the_limit_is_refused_and_keeps_no_slot(sim: Client) -> None:
    sim.spawn(spheres([f"b{i}" for i in range(BALLS)], np.zeros((BALLS, 3)), 0.01,
                      static=True))
    slots = sim.snapshots()
    with pytest.raises(ResourceLimitError, match="blob") as refused:
        sim.call("snapshot", {"slot": "big", "blob": True})
    _refused(refused)
    assert sim.snapshots() == slots
    assert sim.snapshot("big").slot == "big"  # without the blob it is kept
    sim.call("delete_snapshot", {"slot": "big"})


def test_any_other_reply_over_the_limit_is_refused_once_encoded(sim: Client) -> None:
    names = [f"b{i}" for i in range(BALLS)]
    sim.spawn(spheres(names, np.column_stack([np.arange(BALLS) * 0.1, np.zeros((BALLS, 2))]),
                      0.01, static=True))
    before = sim.status().step
    with pytest.raises(ResourceLimitError, match="get_states") as refused:
        sim.get_states()
    _refused(refused)
    assert sim.get_states(names[:10]).poses.shape == (10, 7)
    with pytest.raises(ResourceLimitError, match="list"):
        sim.list()  # 2,000 entities' rows: over the limit too
    assert sim.status().step == before  # still serving


def test_a_get_shapes_reply_whose_triangles_pass_the_limit_is_refused_up_front(
        sim: Client) -> None:
    # 10,000 vertices (240 kB) of which one tetrahedron is made: quick for MuJoCo to build.
    vertices = np.random.default_rng(35).uniform(-0.1, 0.1, (10_000, 3))
    faces = [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]
    sim.spawn(meshes(["disc"], [[0, 0, 0.5]], vertices, faces, static=True),
              spheres(["ball"], [[1, 0, 0.5]], 0.05, static=True))
    with pytest.raises(ResourceLimitError, match="get_shapes reply") as refused:
        sim.get_shapes()
    _refused(refused)
    assert [shape.kind for shape in sim.get_shapes(["ball"])["ball"]] == ["sphere"]


def _pile(sim: Client) -> list[str]:
    """BALLS falling balls in a row: the reads of all of them pass LIMIT."""
    names = [f"b{i}" for i in range(BALLS)]
    rows = np.column_stack([np.arange(BALLS) * 0.1, np.zeros(BALLS), np.ones(BALLS)])
    sim.spawn(spheres(names, rows, 0.01))
    return names


STEPPING = [("step", {"count": 1}), ("run_until", {"sim_time": 0.1}),
            ("run_until", {"sim_time": 0.1, "until_rest": {"speed": 0.1, "every": 0.01}})]


def test_a_step_whose_reads_pass_the_limit_is_refused_before_any_step(sim: Client) -> None:
    """Refused once its reply was encoded, such a step had changed the world first."""
    names = _pile(sim)
    before = sim.get_states(names[:100])
    for op, args in STEPPING:
        with pytest.raises(ResourceLimitError, match="no step was taken") as refused:
            sim.call(op, {**args, "read": names})
        _refused(refused)
    assert sim.status().step == 0
    assert np.array_equal(sim.get_states(names[:100]).poses, before.poses)
    assert sim.step_and_read(1, names[:10]).poses.shape == (10, 7)


def test_set_joint_states_whose_reads_pass_the_limit_sets_nothing(sim: Client) -> None:
    names = _pile(sim)
    load_robot(sim, "pendulum5")
    joint = next(j.name for j in joints(sim) if j.type in ("revolute", "continuous"))
    before = sim.call("get_joint_states", {"names": [joint]})["positions"]
    with pytest.raises(ResourceLimitError, match="no joint was set") as refused:
        sim.call("set_joint_states", {"names": [joint], "positions": 0.5, "read": names})
    _refused(refused)
    assert sim.call("get_joint_states", {"names": [joint]})["positions"] == before


@pytest.mark.parametrize("name_length", [1, 31, 32, 128])
def test_the_estimate_of_a_step_reply_is_never_under_it(name_length: int) -> None:
    """Refused up front by an estimate, a step must not be refused again once it ran: the
    estimate is at least the encoded reply, and not much more (names of 4-byte characters)."""
    rng = np.random.default_rng(35)
    bodies = [f"{i:04d}" + "\U0001f600" * (name_length - 4) for i in range(300)]
    knees = [f"j{i}" for i in range(7)]
    result = {"steps": 10**9, "names": bodies, "at_rest": False,
              "poses": pack_f64(rng.random((300, 7))), "twists": pack_f64(rng.random((300, 6))),
              "joints": {"names": knees, **{k: pack_f64(rng.random(7)) for k in
                                            ("positions", "velocities", "efforts")}}}
    size = len(encode_reply(Reply(ResultCode.OK, result=result, step=10**9, sim_time=1e9)))
    assert size <= reads_size(bodies, knees) <= size + 2048
