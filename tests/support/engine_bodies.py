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

# A lever on a fixed base: the arm's mass and collision box lie 0.2 m along x from its
# link frame, which sits on the hinge, 1 m above the base.
LEVER = """<robot name="lever">
<link name="base"><inertial><mass value="5"/>
  <inertia ixx=".1" ixy="0" ixz="0" iyy=".1" iyz="0" izz=".1"/></inertial>
  <collision><geometry><box size=".1 .1 .1"/></geometry></collision></link>
<link name="arm"><inertial><origin xyz="0.2 0 0"/><mass value="1"/>
  <inertia ixx=".01" ixy="0" ixz="0" iyy=".01" iyz="0" izz=".01"/></inertial>
  <collision><origin xyz="0.2 0 0"/><geometry><box size=".4 .05 .05"/></geometry></collision>
</link>
<joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
  <origin xyz="0 0 1"/><axis xyz="0 1 0"/>
  <limit lower="-1" upper="1" effort="100" velocity="10"/></joint></robot>"""


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


def slide(engine_name: str, ground_friction: float, box_friction: float) -> float:
    """How far (m) a box launched at 2 m/s along x slides in a second on a fresh engine."""
    engine = create_engine(engine_name)
    try:
        engine.spawn([ground(friction=ground_friction),
                      BodyGroup("box", (0.05, 0.05, 0.05), ["box"], at([0, 0, 0.05]),
                                friction=box_friction, twists=np.array([[2.0, 0, 0, 0, 0, 0]]))])
        seconds(engine, 1.0)
        return float(engine.get_states(["box"])[0][0, 0])
    finally:
        engine.close()
