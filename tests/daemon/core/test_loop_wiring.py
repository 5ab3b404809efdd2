"""The loop is wired once: what it is given (core/wiring.py) comes at construction, cannot be
set afterwards, and the composition root sets no attribute of it; everything the loop
publishes (telemetry, events, state streams) leaves through its one outlet."""

from __future__ import annotations

import ast
import dataclasses
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import msgpack
import numpy as np
import pytest

import galton.daemon
from galton.daemon.core.calls import Call
from galton.daemon.core.clock import WorldClock
from galton.daemon.core.loop import SimLoop
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import BodyGroup, ResultCode, decode_reply, encode_request

SERVER = Path(galton.daemon.__file__).parent / "server.py"


@pytest.fixture
def published() -> list[tuple[str, bytes]]:
    return []


@pytest.fixture
def loop(published: list[tuple[str, bytes]]) -> Iterator[SimLoop]:
    before = sys.getswitchinterval()
    wiring = LoopWiring("wired", publish=lambda topic, data: published.append((topic, data)),
                        engine_factory=create_engine, snapshot_key=b"k" * 32,
                        advertised=lambda: {"zmq": "tcp://127.0.0.1:1"})
    sim = SimLoop(World(create_engine("mujoco")), wiring)
    yield sim
    sim.world.engine.close()
    sys.setswitchinterval(before)


def handle(loop: SimLoop, op: str, args: dict | None = None) -> dict:
    answers: list[bytes] = []
    loop.handle(Call(op, encode_request(op, args, client="me"), answers.append))
    reply = decode_reply(answers[0])
    assert reply.code == ResultCode.OK, reply
    return reply.result


def test_what_the_wiring_gave_cannot_be_set_afterwards(loop: SimLoop) -> None:
    assert (loop.instance, loop.snapshot_key) == ("wired", b"k" * 32)
    for name in ("instance", "limits", "snapshot_key", "engine_factory", "client_alive",
                 "advertised"):
        with pytest.raises(AttributeError):
            setattr(loop, name, None)
    with pytest.raises(dataclasses.FrozenInstanceError):
        loop.wiring.snapshot_key = None  # type: ignore[misc]


def test_capabilities_asks_the_fronts_what_they_advertise(loop: SimLoop) -> None:
    assert handle(loop, "capabilities")["zmq"] == "tcp://127.0.0.1:1"


def test_telemetry_events_and_streams_leave_through_the_one_outlet(
        loop: SimLoop, published: list[tuple[str, bytes]]) -> None:
    loop.world.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["ball"],
                                poses=np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]]))])
    stream = handle(loop, "stream_states", {"rate": 10.0})
    handle(loop, "play")
    loop.publish_telemetry(time.monotonic())
    loop.streams.publish_due(loop, time.monotonic())
    by_topic = {topic: msgpack.unpackb(data) for topic, data in published}
    assert by_topic["events"]["instance"] == "wired"
    assert by_topic["events"]["state"] == "playing"
    assert by_topic["telemetry"]["instance"] == "wired"
    assert by_topic[stream["topic"]]["names"] == ["ball"]


def test_the_clock_is_read_by_name(loop: SimLoop) -> None:
    loop.world.step(3)
    clock = loop.status_board
    assert clock.clock.step == 0  # the physics thread swaps a new reading in when it answers
    handle(loop, "capabilities")
    assert clock.clock == WorldClock(3, pytest.approx(3 * loop.world.engine.timestep),
                                     loop.world.engine.timestep, 0, False)
    assert loop.status().step == clock.clock.step == 3


def loop_assignments(source: str) -> list[str]:
    """Every assignment to an attribute of something's ``loop`` (``self.loop.x = ...``,
    ``daemon.loop.x += ...``), and every ``setattr`` on one."""
    found = []
    for node in ast.walk(ast.parse(source)):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign)):
            targets = [node.target]
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                and node.func.id == "setattr" and node.args:
            targets = [ast.Attribute(node.args[0], "?")]
        found += [ast.unparse(target) for target in targets
                  if isinstance(target, ast.Attribute)
                  and isinstance(target.value, ast.Attribute) and target.value.attr == "loop"]
    return found


def test_the_composition_root_sets_no_attribute_of_the_loop() -> None:
    assert loop_assignments(SERVER.read_text()) == []


def test_a_late_assignment_is_seen() -> None:
    source = ("def wire(self, daemon):\n    self.loop.snapshot_key = b''\n"
              "    daemon.loop.rtf += 1\n    setattr(daemon.loop, 'x', 1)\n"
              "    self.loop = None\n")
    assert loop_assignments(source) == ["self.loop.snapshot_key", "daemon.loop.rtf",
                                        "daemon.loop.?"]
