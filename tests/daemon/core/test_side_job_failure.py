"""A side world whose engine fails while it steps fails its own step request, and the
live world plays on (the failure is injected into the side world's engine: no real
engine fails on demand)."""

from __future__ import annotations

import sys
from collections.abc import Iterator

import pytest

from galton.daemon.core.calls import Call
from galton.daemon.core.loop import SimLoop
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import ResultCode, SimState, decode_reply, encode_request


@pytest.fixture
def loop() -> Iterator[SimLoop]:
    before = sys.getswitchinterval()
    sim = SimLoop(World(create_engine("mujoco")),
                  LoopWiring("test", engine_factory=create_engine))
    yield sim
    for world in sim.side.values():
        world.engine.close()
    sim.world.engine.close()
    sys.setswitchinterval(before)


def handle(loop: SimLoop, op: str, args: dict | None = None) -> list[bytes]:
    answers: list[bytes] = []
    loop.handle(Call(op, encode_request(op, args), answers.append))
    return answers


def test_a_failing_side_engine_fails_its_job_and_not_the_live_world(loop: SimLoop) -> None:
    assert decode_reply(handle(loop, "create_world", {"name": "side"})[0]).code == ResultCode.OK
    assert decode_reply(handle(loop, "play", {"rtf": 0.0})[0]).code == ResultCode.OK
    side = loop.side["side"]

    def fail(count: int) -> None:
        raise RuntimeError("injected engine failure")
    side.engine.step = fail  # type: ignore[method-assign]
    answers = handle(loop, "step", {"count": 100, "world": "side"})
    assert answers == [] and loop.job is not None
    loop.stepping.advance()
    assert len(answers) == 1
    reply = decode_reply(answers[0])
    assert reply.code == ResultCode.OPERATION_FAILED
    assert "injected engine failure" in reply.message
    assert loop.job is None and loop.state == SimState.PLAYING
