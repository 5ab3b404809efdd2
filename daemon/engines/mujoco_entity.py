"""What the MuJoCo engine's parts share: its entities' books, and MuJoCo's refusals as typed
errors."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines import mujoco_pool as mp
from galton.protocol import GaltonError, InvalidArgumentError, ResourceLimitError

GEOM = mujoco.mjtObj.mjOBJ_GEOM
BODY = mujoco.mjtObj.mjOBJ_BODY
# What MuJoCo raises for a model or a change it cannot take (FatalError: its mju_error).
MUJOCO_ERRORS = (ValueError, TypeError, RuntimeError, mujoco.FatalError)
# Body names the engine keeps for itself: the world body's and the parked bodies'.
WORLD = "world"


@dataclass(eq=False)
class Entity:
    """An entity's spec body and what the engine must remember about it."""

    body: Any
    static: bool
    source: str = "spawn"  # "spawn", "model" (a model's root) or "link"
    friction: float | None = None
    restitution: float | None = None
    initial_pose: np.ndarray | None = None
    key: mp.Key | None = None  # its pool kind while its compiled values are still that kind's
    parts: tuple[str, ...] = ()  # a model root's links' names (taken while it lives)
    model: str | None = None  # a model root's or link's root entity

    def geoms(self) -> list[Any]:
        return [self.body.first_geom()] if self.source == "spawn" else \
            self.body.find_all(GEOM)


def mujoco_error(exc: Exception, what: str) -> GaltonError:
    """A typed error for MuJoCo's refusal, in its words: too big is a resource limit."""
    words = str(exc)
    if "allocate memory" in words or "must be less than" in words:
        return ResourceLimitError(f"{what}: MuJoCo cannot hold the world ({words})")
    return InvalidArgumentError(f"{what}: {words}")
