"""Status replies are answered from one reading of the loop's status values, and a repeated
poll of unchanged values reuses the last reply's bytes; any change of what status says is
seen at once."""

from __future__ import annotations

import gc
import sys
import weakref
from collections.abc import Iterator

import pytest

from galton.daemon.core.calls import Call
from galton.daemon.core.loop import SimLoop
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import ResultCode, decode_reply, encode_request


@pytest.fixture
def loop() -> Iterator[SimLoop]:
    before = sys.getswitchinterval()
    sim = SimLoop(World(create_engine("mujoco")),
                  LoopWiring("test", engine_factory=create_engine))
    yield sim
    sim.world.engine.close()
    sys.setswitchinterval(before)


def poll(loop: SimLoop, args: dict | None = None) -> bytes:
    answers: list[bytes] = []
    loop.intake.dispatch(Call("status", encode_request("status", args), answers.append))
    assert len(answers) == 1
    return answers[0]


def handle(loop: SimLoop, op: str, args: dict | None = None) -> None:
    answers: list[bytes] = []
    loop.handle(Call(op, encode_request(op, args), answers.append))
    assert answers and decode_reply(answers[0]).code == ResultCode.OK


def test_an_unchanged_status_is_answered_with_the_same_bytes(loop: SimLoop) -> None:
    first = poll(loop)
    assert poll(loop) is first
    assert decode_reply(first).result["state"] == "stopped"


def test_a_state_change_is_seen_by_the_next_poll(loop: SimLoop) -> None:
    poll(loop)
    handle(loop, "pause")
    assert decode_reply(poll(loop)).result["state"] == "paused"
    handle(loop, "set_rtf", {"rtf": 2.5})
    assert decode_reply(poll(loop)).result["target_rtf"] == 2.5


def test_steps_are_seen_by_the_next_poll(loop: SimLoop) -> None:
    poll(loop)
    loop.world.step(7)
    loop.refresh_clock()
    reply = decode_reply(poll(loop))
    assert (reply.step, reply.result["step"]) == (7, 7)
    assert reply.sim_time == pytest.approx(7 * loop.world.engine.timestep)


def test_a_new_world_is_seen_by_the_next_poll(loop: SimLoop) -> None:
    assert decode_reply(poll(loop)).result["engine"] == "mujoco"
    handle(loop, "load_world", {"engine": "pybullet"})
    assert decode_reply(poll(loop)).result["engine"] == "pybullet"


def test_a_bad_request_is_refused_after_a_cached_answer(loop: SimLoop) -> None:
    good = poll(loop)
    refused = decode_reply(poll(loop, {"world": "elsewhere"}))
    assert refused.code == ResultCode.NOT_FOUND
    assert "elsewhere" in refused.message
    assert poll(loop) is good


def test_a_refused_status_leaves_nothing_for_the_collector(loop: SimLoop) -> None:
    """Issue 46: a refused status kept its request in a reference cycle (the error, its
    traceback, the frame that held the error), so each 50 MB one stayed in memory until
    a full collection; now the call is freed as soon as it is answered."""
    answers: list[bytes] = []
    call = Call("status", b"\xc1" * 1000, answers.append)  # 0xc1: never valid msgpack
    collecting = gc.isenabled()
    gc.disable()
    try:
        loop.intake.dispatch(call)
        freed = weakref.ref(call)
        del call
        assert freed() is None
    finally:
        if collecting:
            gc.enable()
    assert decode_reply(answers[0]).code == ResultCode.MALFORMED_REQUEST


def test_a_side_worlds_status_is_handed_to_the_physics_thread(loop: SimLoop) -> None:
    """The caller's thread answers the live world's status; a side world's waits in the
    inbox and the physics thread answers it, stamped with that world's clock."""
    handle(loop, "create_world", {"name": "side"})
    answers: list[bytes] = []
    loop.intake.dispatch(Call("status", encode_request("status", {"world": "side"}),
                              answers.append))
    assert answers == []
    waiting = loop.intake.inbox.get_nowait()
    assert isinstance(waiting, Call)
    loop.handle(waiting)
    reply = decode_reply(answers[0])
    assert (reply.code, reply.result["world"], reply.result["state"]) == (
        ResultCode.OK, "side", "stopped")
