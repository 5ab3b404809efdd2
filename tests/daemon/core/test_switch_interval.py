"""The physics loop tunes Python's switch interval to whether its engine holds the GIL."""

from __future__ import annotations

import sys
from collections.abc import Iterator

import pytest

from galton.daemon.core.loop import DEFAULT_SWITCH_INTERVAL_S, SHORT_SWITCH_INTERVAL_S, SimLoop
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World


@pytest.fixture(autouse=True)
def keep_switch_interval() -> Iterator[None]:
    before = sys.getswitchinterval()
    yield
    sys.setswitchinterval(before)


@pytest.mark.parametrize(("engine", "expected"), [
    ("pybullet", SHORT_SWITCH_INTERVAL_S), ("mujoco", DEFAULT_SWITCH_INTERVAL_S)])
def test_the_switch_interval_follows_the_engine(engine: str, expected: float) -> None:
    world = World(create_engine(engine))
    try:
        SimLoop(world, LoopWiring("test"))
        assert sys.getswitchinterval() == pytest.approx(expected)
    finally:
        world.engine.close()
