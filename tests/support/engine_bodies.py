"""Helpers of the engine tests that drive an engine in the test's own process, through its
public interface (no daemon): poses, a ground, simulated seconds, and the engine fixture."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import BodyGroup


def at(*positions: list[float]) -> np.ndarray:
    """Poses at ``positions``, unturned (one row each: x, y, z, qx, qy, qz, qw)."""
    out = np.zeros((len(positions), 7))
    out[:, :3] = positions
    out[:, 6] = 1.0
    return out


def ground(**options: Any) -> BodyGroup:
    """A static 10 m × 10 m plane at z = 0 named ``ground``."""
    return BodyGroup("plane", (5.0, 5.0), ["ground"], at([0, 0, 0]), static=True, **options)


def seconds(engine: Engine, duration: float) -> None:
    """Step ``engine`` for ``duration`` simulated seconds."""
    engine.step(round(duration / engine.timestep))


def engine_fixture(name: str) -> Callable[[], Iterator[Engine]]:
    """A test module's ``engine`` fixture: a fresh ``name`` engine per test, closed after."""

    @pytest.fixture
    def engine() -> Iterator[Engine]:
        made = create_engine(name)
        yield made
        made.close()
    return engine
