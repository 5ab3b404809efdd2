"""A world behind its clock catches up chunk after chunk, but a state sample that falls due
ends the catch-up, so a slow world still streams at the rate its stream asked."""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from galton.daemon.core.calls import Call
from galton.daemon.core.loop import SimLoop
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import BodyGroup, ResultCode, decode_reply, encode_request

BALLS = 200


@pytest.fixture
def loop() -> Iterator[SimLoop]:
    before = sys.getswitchinterval()
    world = World(create_engine("mujoco"))
    poses = np.zeros((BALLS, 7))
    poses[:, 0], poses[:, 2], poses[:, 6] = np.arange(BALLS) * 0.2, 1.0, 1.0
    world.spawn([BodyGroup(shape="sphere", size=(0.05,), names=[f"b{i}" for i in range(BALLS)],
                           poses=poses)])
    sim = SimLoop(world, LoopWiring("test", engine_factory=create_engine))
    yield sim
    sim.world.engine.close()
    sys.setswitchinterval(before)


def handle(loop: SimLoop, op: str, args: dict | None = None) -> None:
    answers: list[bytes] = []
    loop.handle(Call(op, encode_request(op, args, client="viewer"), answers.append))
    assert answers and decode_reply(answers[0]).code == ResultCode.OK, decode_reply(answers[0])


def behind_its_clock(loop: SimLoop) -> int:
    """Play at RTF 1,000 and let 30 ms pass: far more steps are due than one chunk holds.
    Returns the chunk size the loop has learnt for this world."""
    loop.world.step(20)  # the loop learns the step's cost from its own chunks first
    loop.stepping.run_steps(20)
    handle(loop, "play", {"rtf": 1000.0})
    threading.Event().wait(0.03)  # a lag to make, not a synchronisation
    return loop.stepping.chunk_size()


def test_a_due_sample_ends_the_catch_up_after_one_chunk(loop: SimLoop) -> None:
    handle(loop, "stream_states", {"rate": 60.0})  # its first sample is due at once
    chunk = behind_its_clock(loop)
    before = loop.world.step_index
    loop.stepping.play_due()
    assert loop.world.step_index - before == chunk


def test_without_a_stream_the_catch_up_runs_several_chunks(loop: SimLoop) -> None:
    chunk = behind_its_clock(loop)
    before = loop.world.step_index
    loop.stepping.play_due()
    assert loop.world.step_index - before > chunk
