"""The PyBullet engine's perception (mixed into PybulletEngine): pictures
(render.py), ray casts (rays.py) and contacts (contacts.py), all
naming what they show by entity, through PyBullet's (body, link) codes."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.base import CameraView, ContactPoints, RayHits
from galton.daemon.engines.pybullet import contacts as pybullet_contacts
from galton.daemon.engines.pybullet import rays as pybullet_rays
from galton.daemon.engines.pybullet import render as pybullet_render
from galton.daemon.engines.pybullet.calls import engine_call
from galton.daemon.engines.pybullet.ray_shapes import EXACT
from galton.daemon.engines.pybullet.rebuild import Body
from galton.daemon.engines.pybullet.robots import Robots


class Perception:
    """render, raycast and contacts over the engine's records of bodies and models."""

    _bc: BulletClient
    bodies: dict[str, Body]
    robots: Robots

    def _codes(self) -> dict[int, str]:
        return pybullet_render.entity_codes(self._bc, self.bodies, self.robots)

    @engine_call
    def render(self, cameras: Sequence[CameraView]
               ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
        """TinyRenderer, one getCameraImage per camera (render.py)."""
        return pybullet_render.render(self._bc, self._codes(), cameras)

    @engine_call
    def raycast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
                ) -> RayHits:
        """rayTestBatch, hits on spawned primitives made exact (rays.py)."""
        primitives = {pybullet_render.code(body.uid, -1): (body.shape, body.size)
                      for body in self.bodies.values() if body.shape in EXACT}
        return RayHits(*pybullet_rays.raycast(self._bc, self._codes(), primitives, origins,
                                              directions, max_length))

    @engine_call
    def contacts(self, names: Sequence[str] | None) -> ContactPoints:
        """getContactPoints of the last step, normals from the first entity to the second."""
        if names is not None:
            self.robots.check_entities(self.bodies, names)
        wanted = None if names is None else set(names)
        return ContactPoints(*pybullet_contacts.contacts(self._bc, self._codes(), wanted))
