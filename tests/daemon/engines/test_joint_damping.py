"""A joint's own damping set through the engine contract (Engine.set_joint_damping) on
every engine: a damped pendulum swings less than a free one, ``joints`` reports the value,
and a snapshot restored into a fresh engine, and a clone, carry it (they swing as the
original does from then on)."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest
from support.daemons import ENGINES
from support.models import G, Pendulum

from galton.daemon.engines import create_engine
from galton.daemon.engines.base import Engine
from galton.protocol import NotFoundError

DT = 0.002
HINGE = ["hinge"]
START = 1.0  # rad
DAMPING = 0.5  # N·m·s/rad: a pivot inertia of 0.26 kg·m² loses half its swing in ~0.7 s


@pytest.fixture(params=ENGINES)
def engine(request: pytest.FixtureRequest) -> Iterator[Engine]:
    made = create_engine(request.param)
    made.set_params({"timestep": DT, "gravity": [0.0, 0.0, -G]})
    made.load_model("urdf", Pendulum().urdf(), None, "", fixed_base=True)
    made.set_joint_states(HINGE, np.array([START]), np.array([0.0]))
    yield made
    made.close()


def swing(engine: Engine, seconds: float = 1.0) -> np.ndarray:
    """The hinge's angle every 10 steps for ``seconds``."""
    angles = []
    for _ in range(round(seconds / (10 * DT))):
        engine.step(10)
        angles.append(float(engine.get_joint_states(HINGE)[0][0]))
    return np.array(angles)


def damping_of(engine: Engine) -> float:
    return next(j.damping for j in engine.joints() if j.name == "hinge")


def test_a_damped_joint_swings_less_and_says_so(engine: Engine) -> None:
    free = engine.clone()
    try:
        engine.set_joint_damping(HINGE, np.array([DAMPING]))
        assert damping_of(engine) == pytest.approx(DAMPING)
        assert damping_of(free) == 0.0  # a clone made before is its own
        damped, undamped = swing(engine), swing(free)
    finally:
        free.close()
    late = slice(len(damped) // 2, None)  # the second half second: the swing's amplitude
    assert np.abs(undamped[late]).max() > 0.9 * START  # no damping: the swing holds
    assert np.abs(damped[late]).max() < 0.8 * np.abs(undamped[late]).max()


def test_snapshots_and_clones_carry_the_damping(engine: Engine) -> None:
    engine.set_joint_damping(HINGE, np.array([DAMPING]))
    engine.step(50)
    restored = type(engine)()
    clone = engine.clone()
    try:
        restored.restore(engine.snapshot())
        assert damping_of(restored) == pytest.approx(DAMPING)
        assert damping_of(clone) == pytest.approx(DAMPING)
        reference = swing(engine, 0.4)
        np.testing.assert_allclose(swing(restored, 0.4), reference, atol=1e-9)
        np.testing.assert_allclose(swing(clone, 0.4), reference, atol=1e-9)
    finally:
        restored.close()
        clone.close()


def test_damping_addresses_one_dof_joints_only(engine: Engine) -> None:
    with pytest.raises(NotFoundError):
        engine.set_joint_damping(["no_such_joint"], np.array([1.0]))
