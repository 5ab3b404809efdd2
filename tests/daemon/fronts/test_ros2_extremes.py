"""The fuzzer's extreme poses and twists (galton.client.fuzz.extremes) through the ROS 2
front, on every engine (issue 46): SpawnEntity's initial_pose and SetEntityState's pose and
twist at the ends of float64 reach the same bounds as a native request. Each gets one reply
with a refusal code, nothing is applied, and the world still steps (ODE aborted on them)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from support.daemons import ENGINES
from support.ros2_client import Cdr, RosClient, put_pose_stamped

from galton.client import EmbeddedDaemon
from galton.client.fuzz.extremes import Quaternion, Vector, extreme_poses, extreme_twists

OK, NOT_FOUND = 1, 2
SPAWN_INVALID_POSE, SET_STATE_INVALID_POSE = 109, 101  # simulation_interfaces' codes
IDENTITY: Quaternion = (0.0, 0.0, 0.0, 1.0)
ZERO6 = (0.0,) * 6


@pytest.fixture(scope="module", params=ENGINES)
def ros(request: pytest.FixtureRequest) -> Iterator[tuple[RosClient, EmbeddedDaemon]]:
    engine = request.param
    with EmbeddedDaemon(engine, instance=f"rosx{engine}", extra_args=["--ros2"]) as running:
        client = RosClient(running.endpoint)
        try:
            yield client, running
        finally:
            client.close()


def call(ros: RosClient, node: str, service: str, request: bytes) -> Cdr:
    """One call (RosClient checks that exactly one reply came)."""
    name = "".join(part.title() for part in service.split("_"))
    return ros.call(f"/{node}/{service}", name, request)[0]


def spawn_request(name: str, position: Vector, quaternion: Quaternion) -> bytes:
    request = Cdr.writer().put_string(name).put("B", 0).put_string(
        "galton://sphere?size=0.05").put_string("").put_string("")
    put_pose_stamped(request, "", position, quaternion)
    return bytes(request.data)


def set_state_request(name: str, position: Vector, quaternion: Quaternion,
                      twist: tuple[float, ...], set_pose: bool, set_twist: bool) -> bytes:
    request = Cdr.writer().put_string(name).put("iI", 0, 0).put_string("")
    request.put("3d", *position).put("4d", *quaternion)
    request.put("6d", *twist).put("6d", *ZERO6)
    request.put("B", set_pose).put("B", set_twist).put("B", 0)  # the acceleration: never
    return bytes(request.data)


def entity_state(ros: RosClient, node: str, name: str) -> tuple[int, tuple[float, ...]]:
    """GetEntityState's result code, and the pose and twist it read (empty if refused)."""
    reply = call(ros, node, "get_entity_state", bytes(Cdr.writer().put_string(name).data))
    code = reply.get_result()[0]
    if code != OK:
        return code, ()
    reply.get("iI")
    reply.get_string()
    return code, (*reply.get("3d"), *reply.get("4d"), *reply.get("6d"))


def test_extreme_poses_and_twists_through_ros2_are_refused_and_change_nothing(
        ros: tuple[RosClient, EmbeddedDaemon]) -> None:
    client, running = ros
    node = running.instance
    assert call(client, node, "spawn_entity",
                spawn_request("b", (0.0, 0.0, 1.0), IDENTITY)).get_result() == (OK, "")
    code, kept = entity_state(client, node, "b")
    assert code == OK
    for n, (position, quaternion) in enumerate(extreme_poses()):
        what = f"{position} {quaternion}"
        spawned = call(client, node, "spawn_entity", spawn_request(f"x{n}", position,
                                                                   quaternion)).get_result()
        assert spawned[0] != OK, f"SpawnEntity {what} was accepted"
        if quaternion != IDENTITY:
            assert spawned[0] == SPAWN_INVALID_POSE, (what, spawned)
        assert entity_state(client, node, f"x{n}")[0] == NOT_FOUND, f"SpawnEntity {what}"
        moved = call(client, node, "set_entity_state", set_state_request(
            "b", position, quaternion, ZERO6, True, False)).get_result()
        assert moved[0] != OK, f"SetEntityState {what} was accepted"
        if quaternion != IDENTITY:
            assert moved[0] == SET_STATE_INVALID_POSE, (what, moved)
        assert entity_state(client, node, "b") == (OK, kept), f"SetEntityState {what}"
    for twist in extreme_twists():
        sped = call(client, node, "set_entity_state", set_state_request(
            "b", (0.0, 0.0, 1.0), IDENTITY, twist, False, True)).get_result()
        assert sped[0] != OK, f"SetEntityState twist {twist} was accepted"
        assert entity_state(client, node, "b") == (OK, kept), f"SetEntityState {twist}"
    step = call(client, node, "step_simulation", bytes(Cdr.writer().put("Q", 10).data))
    assert step.get_result() == (OK, "")
    code, after = entity_state(client, node, "b")
    assert code == OK and after[2] < kept[2]  # it fell from where it was put, untouched
    assert running.process is not None and running.process.poll() is None
