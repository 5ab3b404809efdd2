"""A DART snapshot's layout: what one spawned body or one loaded model becomes as plain
data, and the checked reading of the numbers that come back (snapshot/__init__.py takes
and restores the world)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from galton.daemon.engines.dart import models
from galton.daemon.engines.dart import spawn as spawning
from galton.protocol import BodyProperties
from galton.protocol import mesh as mesh_wire

FORMAT = "galton-dart-1"


def dynamic(body: spawning.Body) -> dict[str, list[float]]:
    """A skeleton's generalized positions and velocities, as the float64 DART holds."""
    return {"positions": [float(v) for v in body.skeleton.getPositions()],
            "velocities": [float(v) for v in body.skeleton.getVelocities()]}


def body_item(body: spawning.Body) -> dict[str, Any]:
    """A spawned body as plain data."""
    return {"kind": "body", "name": body.name, "shape": body.shape,
            "size": list(body.size), "static": body.static,
            "mass": None if body.static else body.mass, "friction": body.friction,
            "restitution": body.restitution,
            "follows": [body.follows_friction, body.follows_restitution],
            "rgba": None if body.rgba is None else list(body.rgba),
            "unit_inertia": None if body.unit_inertia is None
            else list(body.unit_inertia),
            "vertices": None if body.mesh is None
            else mesh_wire.pack_vertices(body.mesh[0]),
            "faces": None if body.mesh is None else mesh_wire.pack_faces(body.mesh[1]),
            **dynamic(body)}


def model_item(root: spawning.Body, model: models.Model,
               edits: Sequence[tuple[str, BodyProperties]]) -> dict[str, Any]:
    """A loaded model (its root ``root``) as plain data: its text, and the edits since."""
    return {"kind": "model", "root": root.name, "fmt": model.fmt, "text": model.text,
            "prefix": model.prefix, "fixed_base": model.fixed_base,
            "index": model.index,
            "edits": [[name, props.to_wire()] for name, props in edits], **dynamic(root)}

def vector(values: Any, length: int = 3) -> np.ndarray:
    array = np.asarray(values, dtype=float).reshape(-1)
    if array.shape != (length,):
        raise ValueError(f"expected {length} numbers, got {array.shape[0]}")
    return array


def unit_inertia(value: Any, static: bool) -> tuple[float, ...] | None:
    """A snapshot body's own inertia per kg: three positive finite numbers, or None."""
    if value is None:
        return None
    moments = tuple(float(v) for v in vector(value, 3))
    if static or not all(math.isfinite(v) and v > 0 for v in moments):
        raise ValueError(f"unit_inertia {moments} must be positive, and on a moving body")
    return moments

