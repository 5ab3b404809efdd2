"""Ray casts through ODE's own ray geom: ``dSpaceCollide2`` finds the geoms whose boxes the
ray crosses (in C), ``dCollide`` the closest hit on each; the nearest one wins. A ray does
not see the shape it starts inside (ODE would report where it leaves it): a geom holding the
ray's origin is skipped, by ODE's point-depth queries (a cylinder's by its own test)."""

from __future__ import annotations

import ctypes
import math
from typing import Any

import numpy as np

from galton.daemon.engines.ode.native import (
    BOX,
    CAPSULE,
    CYLINDER,
    LIB,
    NEAR_CALLBACK,
    PLANE,
    SPHERE,
    ContactGeom,
)
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
        self.origin = [0.0, 0.0, 0.0]
        self.callback = NEAR_CALLBACK(self._near)

    def cast(self, origins: np.ndarray, directions: np.ndarray, max_length: float
             ) -> tuple[np.ndarray, list[str], np.ndarray, np.ndarray, np.ndarray]:
        count = len(origins)
        hits, names = np.zeros(count, dtype=bool), [""] * count
        points, normals = np.full((count, 3), math.nan), np.full((count, 3), math.nan)
        distances = np.full(count, math.nan)
        LIB.dGeomRaySetLength(self.ray, float(max_length))
        for k in range(count):
            self.origin = origins[k].tolist()
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
        if holds(other, self.origin):
            return  # the ray starts inside this shape
        normal = tuple(self.hit.normal[:3])
        depth = float(self.hit.depth)
        if self.best is None or depth < self.best[0]:
            self.best = (depth, self.by_geom[other].name, tuple(self.hit.pos[:3]), normal)

    def close(self) -> None:
        LIB.dGeomDestroy(self.ray)


def holds(geom: int, point: list[float]) -> bool:
    """Whether the point lies inside the geom (on its surface counts as outside)."""
    kind = LIB.dGeomGetClass(geom)
    depth = POINT_DEPTH.get(kind)
    if depth is not None:
        return bool(depth(geom, *point) > 0)
    if kind != CYLINDER:
        return False
    local = (ctypes.c_double * 4)()
    LIB.dGeomGetPosRelPoint(geom, *point, local)
    radius, length = ctypes.c_double(), ctypes.c_double()
    LIB.dGeomCylinderGetParams(geom, ctypes.byref(radius), ctypes.byref(length))
    return bool(local[0] ** 2 + local[1] ** 2 < radius.value ** 2
                and abs(local[2]) < length.value / 2)


POINT_DEPTH = {SPHERE: LIB.dGeomSpherePointDepth, BOX: LIB.dGeomBoxPointDepth,
               CAPSULE: LIB.dGeomCapsulePointDepth, PLANE: LIB.dGeomPlanePointDepth}
