"""MuJoCo's own refusal of a mesh: a moving mesh with no volume (MuJoCo cannot give it an
inertia) is INVALID_ARGUMENT, and its mesh asset leaves the spec with its body, so the
world steps on and the next mesh spawns."""

from __future__ import annotations

import numpy as np
import pytest

from galton.client import Client, InvalidArgumentError, meshes, spheres

CORNER = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]])
OPEN = np.array([[0, 1, 2]])  # one triangle: no volume
CLOSED = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])  # a tetrahedron


def test_a_mesh_without_volume_is_refused_and_leaves_nothing(mujoco_sim: Client) -> None:
    mujoco_sim.spawn(spheres(["ball"], [[0, 0, 3]], 0.1))
    with pytest.raises(InvalidArgumentError, match="mesh volume"):
        mujoco_sim.spawn(meshes(["open"], [[0, 0, 1]], CORNER, OPEN))
    assert [e.name for e in mujoco_sim.list()] == ["ball"]
    mujoco_sim.step(10)
    mujoco_sim.spawn(meshes(["tetra"], [[0, 0, 1]], CORNER, CLOSED))
    assert [e.name for e in mujoco_sim.list()] == ["ball", "tetra"]
