"""Every engine refuses a moving plane and a shape the protocol does not know at its own
spawn, whoever calls it, and keeps nothing of the refused request (engines/geometry.py's
check_group for PyBullet and DART; MuJoCo's and ODE's own checks)."""

from __future__ import annotations

import numpy as np
import pytest

from galton.daemon.engines import create_engine
from galton.protocol import BodyGroup, InvalidArgumentError

ENGINES = ("mujoco", "pybullet", "ode", "dart")
AT_ONE_METRE = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]])


@pytest.mark.parametrize("engine_name", ENGINES)
@pytest.mark.parametrize(("shape", "size", "static"), [("plane", (5.0, 5.0), False),
                                                        ("cube", (0.1,), True)])
def test_a_bad_group_is_refused_and_nothing_kept(engine_name: str, shape: str,
                                                  size: tuple[float, ...], static: bool
                                                  ) -> None:
    engine = create_engine(engine_name)
    try:
        group = BodyGroup(shape=shape, size=size, names=["odd"], poses=AT_ONE_METRE,
                          static=static)
        with pytest.raises(InvalidArgumentError):
            engine.spawn([group])
        ball = BodyGroup(shape="sphere", size=(0.05,), names=["ball"], poses=AT_ONE_METRE)
        engine.spawn([ball])  # the engine still serves, with no trace of "odd"
        engine.step(1)
        assert engine.get_states(["ball"])[0].shape[0] == 1
    finally:
        engine.close()
