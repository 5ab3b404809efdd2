"""get_shapes: each entity's collision shapes in its own frame, on every engine."""

from __future__ import annotations

import numpy as np
import pytest

from galton.client import Client, body_group, spheres
from galton.protocol import FeatureUnsupportedError, NotFoundError

URDF = """<robot name="crate"><link name="base">
  <inertial><origin xyz="0.05 0 0"/><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><origin xyz="0 0 0.1"/><geometry><box size="0.2 0.4 0.6"/></geometry></collision>
</link></robot>"""


def test_a_primitive_is_its_own_shape_at_its_origin(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[1.0, 2.0, 3.0]], 0.25, static=True))
    sim.spawn(body_group("cylinder", (0.1, 0.3), ["can"], [[0.0, 0.0, 1.0]], static=True))
    shapes = sim.get_shapes()
    assert list(shapes) == ["ball", "can"]
    [ball], [can] = shapes["ball"], shapes["can"]
    assert (ball.kind, can.kind) == ("sphere", "cylinder")
    np.testing.assert_allclose(ball.size, [0.25, 0.0, 0.0])
    np.testing.assert_allclose(can.size, [0.1, 0.3, 0.0])
    np.testing.assert_allclose(can.pose, [0, 0, 0, 0, 0, 0, 1])
    with pytest.raises(NotFoundError, match="did you mean 'ball'"):
        sim.get_shapes(["bal"])


def test_a_urdf_crate_is_one_box_of_its_size(sim: Client) -> None:
    caps = sim.capabilities()
    if "urdf" not in caps.model_formats:
        pytest.skip(f"{caps.engine} loads no URDF")
    [name] = sim.load_model("urdf", text=URDF, prefix="u_")
    if "model_shapes" not in caps.features:  # the engine says so, and answers so
        with pytest.raises(FeatureUnsupportedError):
            sim.get_shapes([name])
        return
    [crate] = sim.get_shapes([name])[name]
    assert crate.kind == "box"
    np.testing.assert_allclose(crate.size, [0.1, 0.2, 0.3], atol=1e-6)
    # In the link's frame, not its centre of mass's.
    np.testing.assert_allclose(crate.pose[:3], [0.0, 0.0, 0.1], atol=1e-6)
    np.testing.assert_allclose(np.abs(crate.pose[3:]), [0, 0, 0, 1], atol=1e-6)
