"""get_bounds: each entity's world-frame axis-aligned box, from its shape, size and pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from galton.client import Client, body_group, spheres
from galton.protocol import FeatureUnsupportedError, NotFoundError


def test_bounds_follow_shape_size_and_pose(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[1.0, 2.0, 3.0]], 0.25, static=True))
    box = body_group("box", (0.1, 0.2, 0.05), ["crate"], [[0.0, 0.0, 0.5]], static=True)
    box.poses[0, 3:] = [0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4)]  # 90° about z
    sim.spawn(box)
    bounds = sim.get_bounds(["ball", "crate"])
    assert list(bounds) == ["ball", "crate"]
    np.testing.assert_allclose(bounds["ball"], [0.75, 1.75, 2.75, 1.25, 2.25, 3.25], atol=1e-6)
    # Turned a quarter about z, the box's x and y extents swap.
    np.testing.assert_allclose(bounds["crate"], [-0.2, -0.1, 0.45, 0.2, 0.1, 0.55], atol=1e-6)
    assert list(sim.get_bounds()) == ["ball", "crate"]  # no names: every entity


def test_unknown_names_are_not_found(sim: Client) -> None:
    sim.spawn(spheres(["ball"], [[0.0, 0.0, 1.0]], 0.1, static=True))
    with pytest.raises(NotFoundError, match="did you mean 'ball'"):
        sim.get_bounds(["bal"])


URDF = """<robot name="crate"><link name="base">
  <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
  </inertial>
  <collision><geometry><box size="0.2 0.4 0.6"/></geometry></collision>
</link></robot>"""


def test_a_loaded_model_is_bounded_by_its_collision_shapes(sim: Client) -> None:
    formats = sim.capabilities().model_formats
    if "urdf" not in formats:
        pytest.skip(f"{sim.status().engine} loads no URDF")
    [name] = sim.load_model("urdf", text=URDF, prefix="u_")  # a fixed base at the origin
    try:
        bounds = sim.get_bounds([name])
    except FeatureUnsupportedError:
        assert sim.status().engine in ENGINES_WITHOUT_MODEL_BOUNDS
        return
    np.testing.assert_allclose(bounds[name], [-0.1, -0.2, -0.3, 0.1, 0.2, 0.3], atol=1e-6)


# Engines that answer get_bounds for spawned primitives only (docs/protocol.md).
ENGINES_WITHOUT_MODEL_BOUNDS = ("ode", "dart")
