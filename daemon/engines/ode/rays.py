"""Ray casts through ODE's own ray geom: ``dSpaceCollide2`` finds the geoms whose boxes the
ray crosses (in C), ``dCollide`` the closest hit on each; the nearest one wins."""

from __future__ import annotations

import ctypes
import math
from typing import Any

import numpy as np

from galton.daemon.engines.ode.native import LIB, NEAR_CALLBACK, ContactGeom
from galton.daemon.engines.ode.spawn import ASLEEP, AWAKE, RAY, STATIC, Body


class RayCaster:
    """One ray geom, outside every space, aimed anew for each ray."""

    def __init__(self, space: int, by_geom: dict[int, Body]) -> None:
        self.space, self.by_geom = space, by_geom
        self.ray = int(LIB.dCreateRay(None, 1.0))
        LIB.dGeomRaySetClosestHit(self.ray, 1)
        LIB.dGeomSetCategoryBits(self.ray, RAY)
        LIB.dGeomSetCollideBits(self.ray, AWAKE | STATIC | ASLEEP)
        self.hit = ContactGeom()
        self.address = ctypes.addressof(self.hit)
        self.best: tuple[float, str, tuple[float, ...], tuple[float, ...]] | None = None
        self.callback = NEAR_CALLBACK(self._near)

    def cast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
             ) -> tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]:
        count = len(origins)
        hits, names = np.zeros(count, dtype=bool), [""] * count
        points, normals = np.full((count, 3), math.nan), np.full((count, 3), math.nan)
        distances = np.full(count, math.nan)
        LIB.dGeomRaySetLength(self.ray, float(max_length))
        for k in range(count):
            LIB.dGeomRaySet(self.ray, *origins[k].tolist(), *directions[k].tolist())
            self.best = None
            LIB.dSpaceCollide2(self.ray, self.space, None, self.callback)
            found = self._found()
            if found is not None:
                distances[k], names[k], point, normal = found
                hits[k], points[k], normals[k] = True, point, normal
        return hits, names, points, normals, distances

    def _found(self) -> tuple[float, str, tuple[float, ...], tuple[float, ...]] | None:
        return self.best

    def _near(self, _data: Any, g1: int, g2: int) -> None:
        other = g2 if g1 == self.ray else g1
        if not LIB.dCollide(self.ray, other, 1, self.address, ctypes.sizeof(ContactGeom)):
            return
        depth = float(self.hit.depth)
        if self.best is None or depth < self.best[0]:
            self.best = (depth, self.by_geom[other].name, tuple(self.hit.pos[:3]),
                         tuple(self.hit.normal[:3]))

    def close(self) -> None:
        LIB.dGeomDestroy(self.ray)
