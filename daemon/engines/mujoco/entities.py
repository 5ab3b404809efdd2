"""What the MuJoCo engine's parts share: its entities' records, and MuJoCo's refusals as typed
errors."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco import parked as mp
from galton.protocol import GaltonError, InvalidArgumentError, ResourceLimitError

GEOM = mujoco.mjtObj.mjOBJ_GEOM
BODY = mujoco.mjtObj.mjOBJ_BODY
# What MuJoCo raises for a model or a change it cannot take (FatalError: its mju_error).
MUJOCO_ERRORS = (ValueError, TypeError, RuntimeError, mujoco.FatalError)
# Body names the engine keeps for itself: the world body's and the parked bodies'.
WORLD = "world"


# The spec's lists of assets a model brings (meshes, ...): deleting its bodies leaves them.
ASSET_KINDS = ("meshes", "materials", "textures", "hfields", "skins")


@dataclass(eq=False)
class Assets:
    """The assets one model load brought, and how many of its roots still live."""

    names: set[tuple[str, str]]
    roots: int


def asset_names(spec: mujoco.MjSpec) -> set[tuple[str, str]]:
    return {(kind, element.name) for kind in ASSET_KINDS for element in getattr(spec, kind)}


def drop_assets(spec: mujoco.MjSpec, roots: list[Entity]) -> None:
    """Delete the assets of these removed model roots' loads once no root of theirs lives
    (else a model reloaded under the same prefix would repeat their names)."""
    gone: set[tuple[str, str]] = set()
    for root in roots:
        if root.assets is not None:
            root.assets.roots -= 1
            if root.assets.roots == 0:
                gone |= root.assets.names
    delete_assets(spec, gone)


def delete_assets(spec: mujoco.MjSpec, names: set[tuple[str, str]]) -> None:
    for kind in ASSET_KINDS if names else ():
        for element in list(getattr(spec, kind)):
            if (kind, element.name) in names:
                spec.delete(element)


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
    assets: Assets | None = None  # a model root's load's assets

    def geoms(self) -> list[Any]:
        return [self.body.first_geom()] if self.source == "spawn" else \
            self.body.find_all(GEOM)


def mujoco_error(exc: Exception, what: str) -> GaltonError:
    """A typed error for MuJoCo's refusal, in its words: too big is a resource limit."""
    words = str(exc)
    if "allocate memory" in words or "must be less than" in words:
        return ResourceLimitError(f"{what}: MuJoCo cannot hold the world ({words})")
    return InvalidArgumentError(f"{what}: {words}")


def geom_entities(model: mujoco.MjModel, ids: Mapping[str, int]
                  ) -> tuple[list[str], np.ndarray]:
    """Entity names, and each geom's index into them (-1: no entity's, e.g. parked)."""
    names = list(ids)
    of_body = np.full(model.nbody, -1, np.int32)
    of_body[np.fromiter(ids.values(), np.int64, len(ids))] = np.arange(len(names))
    return names, of_body[model.geom_bodyid]
