"""The PyBullet engine's perception (functions of the engine): pictures
(render.py), ray casts (rays.py) and contacts (contacts.py), all
naming what they show by entity, through PyBullet's (body, link) codes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.base import CameraView, ContactPoints, RayHits
from galton.daemon.engines.pybullet import contacts as pybullet_contacts
from galton.daemon.engines.pybullet import rays as pybullet_rays
from galton.daemon.engines.pybullet import render as pybullet_render
from galton.daemon.engines.pybullet.calls import engine_call
from galton.daemon.engines.pybullet.ray_shapes import EXACT

if TYPE_CHECKING:
    from galton.daemon.engines.pybullet.engine import PybulletEngine


def codes(engine: PybulletEngine) -> dict[int, str]:
    return pybullet_render.entity_codes(engine._bc, engine.bodies, engine.robots)


@engine_call
def render(engine: PybulletEngine, cameras: Sequence[CameraView]
           ) -> tuple[list[dict[str, np.ndarray]], list[str]]:
    """TinyRenderer, one getCameraImage per camera (render.py)."""
    return pybullet_render.render(engine._bc, codes(engine), cameras)


@engine_call
def raycast(engine: PybulletEngine, origins: np.ndarray, directions: np.ndarray,
            max_length: float) -> RayHits:
    """rayTestBatch, hits on spawned primitives made exact (rays.py)."""
    primitives = {pybullet_render.code(body.uid, -1): (body.shape, body.size)
                  for body in engine.bodies.values() if body.shape in EXACT}
    return RayHits(*pybullet_rays.raycast(engine._bc, codes(engine), primitives, origins,
                                          directions, max_length))


@engine_call
def contacts(engine: PybulletEngine, names: Sequence[str] | None) -> ContactPoints:
    """getContactPoints of the last step, normals from the first entity to the second."""
    if names is not None:
        engine.robots.check_entities(engine.bodies, names)
    wanted = None if names is None else set(names)
    return ContactPoints(*pybullet_contacts.contacts(engine._bc, codes(engine), wanted))
