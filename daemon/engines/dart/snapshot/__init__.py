"""Snapshots of a DART world as plain data (its layout: format.py), and their restore into
a fresh engine.

DART keeps no contact state between steps (each step detects contacts and solves them
anew), so a world is its skeletons, in the order they were added, their generalized
positions and velocities, and what the engine holds (targets, wrenches, parameters).
Positions and velocities travel as the float64 numbers DART holds, so a restored world
goes on bit for bit as its source, provided the source's collision detector holds its
skeletons in the same order: ``canonical`` first rebuilds the source world (as
``reset_dynamics`` does), after which both are worlds made afresh in the same order.

``snapshot`` and ``restore`` are functions of the engine (``DartEngine`` delegates to them).
Their first argument is the engine, still named ``self`` as when they were its methods.
"""

from __future__ import annotations

import importlib.metadata
import math
from typing import TYPE_CHECKING, Any

from galton.daemon.engines.base import Target
from galton.daemon.engines.dart import meshes, models
from galton.daemon.engines.dart import spawn as spawning
from galton.daemon.engines.dart.params import PARAMS
from galton.daemon.engines.dart.snapshot import format as snapformat
from galton.daemon.engines.params import check_updates
from galton.protocol import BodyProperties, InvalidArgumentError
from galton.protocol import mesh as mesh_wire

if TYPE_CHECKING:
    from galton.daemon.engines.dart.engine import DartEngine


def snapshot(self: DartEngine, *, canonical: bool = True) -> dict[str, Any]:
    if canonical:
        self._rebuild()
    return {"format": snapformat.FORMAT, "engine": "dart",
            "dartpy": importlib.metadata.version("dartpy"),
            "params": {k: list(v) if isinstance(v, tuple) else v
                       for k, v in self._values.items()},
            "time": float(self._world.getTime()),
            "items": [_item(self, owner) for owner in self._owners],
            "targets": {n: [t.mode, t.target, t.kp, t.kd, t.max_effort]
                        for n, t in self._robots.targets.items()},
            "efforts": dict(self._robots.efforts),
            "damping": self._robots.own_damping(),
            "wrenches": {n: [f.tolist(), t.tolist()]
                         for n, (_, f, t) in self._robots.wrenches.items()}}


def _item(self: DartEngine, owner: str) -> dict[str, Any]:
    body = self._bodies[owner]
    if body.model is None:
        return snapformat.body_item(body)
    return snapformat.model_item(body, self._models[owner], self._edits.get(owner, []))


def restore(self: DartEngine, data: dict[str, Any]) -> None:
    if not isinstance(data, dict) or data.get("format") != snapformat.FORMAT:
        raise InvalidArgumentError(
            f"not a DART snapshot (format {snapformat.FORMAT!r} expected)")
    try:
        _restore(self, data)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise InvalidArgumentError(f"malformed DART snapshot: {type(exc).__name__}: "
                                   f"{exc}") from None


def _restore(self: DartEngine, data: dict[str, Any]) -> None:
    # Bodies of one mesh share its shape, as a spawn group's do: each load takes ms.
    self._loaded_meshes = {}
    self.set_params(check_updates("dart", PARAMS, data["params"]))
    for item in data["items"]:
        if item["kind"] == "body":
            _restore_body(self, item)
        elif item["kind"] == "model":
            _restore_model(self, item)
        else:
            raise ValueError(f"unknown item kind {item['kind']!r}")
    self._world.setTime(float(data["time"]))
    for name, (mode, target, kp, kd, effort) in data["targets"].items():
        self._robots.scalar([name])
        self._robots.targets[name] = Target(str(mode), float(target), float(kp),
                                            float(kd), float(effort))
    self._robots.efforts.update({str(k): float(v) for k, v in data["efforts"].items()})
    self._robots.put_back_damping(data.get("damping", {}))
    for name, (force, torque) in data["wrenches"].items():
        self._robots.wrenches[name] = (self._bodies[name].node,
                                       snapformat.vector(force), snapformat.vector(torque))


def _restore_body(self: DartEngine, item: dict[str, Any]) -> None:
    shape, size = str(item["shape"]), tuple(float(s) for s in item["size"])
    static = bool(item["static"])
    mass = math.nan if static else float(item["mass"])
    follows = item["follows"]
    rgba = None if item["rgba"] is None else tuple(float(c) for c in item["rgba"])
    body = spawning.Body(str(item["name"]), shape, size, static, mass,
                      float(item["friction"]), float(item["restitution"]),
                      bool(follows[0]), bool(follows[1]), None, None, rgba,
                      unit_inertia=snapformat.unit_inertia(item.get("unit_inertia"), static))
    self._check_new([body.name])
    if shape not in ("sphere", "box", "cylinder", "capsule", "plane", "mesh"):
        raise ValueError(f"unknown shape {shape!r}")
    if shape == "mesh":
        where = f"the snapshot's mesh {body.name!r}"
        vertices = mesh_wire.decode_vertices(item["vertices"], f"{where} vertices")
        faces = mesh_wire.decode_faces(item["faces"], len(vertices), f"{where} faces")
        mesh_wire.check_area(vertices, faces, where)
        key = (bytes(item["vertices"]), bytes(item["faces"]))
        if key not in self._loaded_meshes:
            self._loaded_meshes[key] = meshes.mesh_shape(vertices, faces)
        body.mesh, body.mesh_shape = (vertices, faces), self._loaded_meshes[key]
    elif item.get("vertices") is not None or item.get("faces") is not None:
        raise ValueError(f"a {shape} has no vertices or faces")
    spawning.build(body, snapformat.vector(item["positions"], 6),
                   snapformat.vector(item["velocities"], 6))
    self._add(body)


def _restore_model(self: DartEngine, item: dict[str, Any]) -> None:
    skeletons = models.parse(str(item["fmt"]), str(item["text"]), bool(item["fixed_base"]))
    index = int(item["index"])
    skeleton = skeletons[index]
    prefix = str(item["prefix"])
    self._check_new(models.link_names(skeleton, prefix))
    self._add_model(models.Model(
        models.root_name(skeleton, prefix), skeleton, str(item["fmt"]), str(item["text"]),
        prefix, bool(item["fixed_base"]), index))
    for name, wire in item["edits"]:
        self._edit(self._bodies[name], BodyProperties(**wire))
    count = skeleton.getNumDofs()
    skeleton.setPositions(snapformat.vector(item["positions"], count))
    skeleton.setVelocities(snapformat.vector(item["velocities"], count))
