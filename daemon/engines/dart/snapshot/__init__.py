"""Snapshots of a DART world as plain data (its layout: format.py), and their restore into
a fresh engine.

DART keeps no contact state between steps (each step detects contacts and solves them
anew), so a world is its skeletons, in the order they were added, their generalized
positions and velocities, and what the engine holds (targets, wrenches, parameters).
Positions and velocities travel as the float64 numbers DART holds, so a restored world
goes on bit for bit as its source, provided the source's collision detector holds its
skeletons in the same order: ``canonical`` first rebuilds the source world (as
``reset_dynamics`` does), after which both are worlds made afresh in the same order.
"""

from __future__ import annotations

import importlib.metadata
import math
from typing import Any

from galton.daemon.engines.base import Target
from galton.daemon.engines.dart import meshes, models
from galton.daemon.engines.dart import spawn as spawning
from galton.daemon.engines.dart.joints import Robots
from galton.daemon.engines.dart.params import PARAMS
from galton.daemon.engines.dart.snapshot import format as snapformat
from galton.daemon.engines.params import check_updates
from galton.protocol import BodyProperties, InvalidArgumentError
from galton.protocol import mesh as mesh_wire


class Snapshots:
    """The engine's part that writes and reads snapshots (DartEngine sets the attributes)."""

    _world: Any
    _values: dict[str, Any]
    _bodies: dict[str, spawning.Body]
    _robots: Robots
    _owners: list[str]
    _models: dict[str, models.Model]
    _edits: dict[str, list[tuple[str, BodyProperties]]]
    _loaded_meshes: dict[tuple[bytes, bytes], Any]  # during a restore: mesh -> its shape

    def snapshot(self, *, canonical: bool = True) -> dict[str, Any]:
        if canonical:
            self._rebuild()  # type: ignore[attr-defined]
        return {"format": snapformat.FORMAT, "engine": "dart",
                "dartpy": importlib.metadata.version("dartpy"),
                "params": {k: list(v) if isinstance(v, tuple) else v
                           for k, v in self._values.items()},
                "time": float(self._world.getTime()),
                "items": [self._item(owner) for owner in self._owners],
                "targets": {n: [t.mode, t.target, t.kp, t.kd, t.max_effort]
                            for n, t in self._robots.targets.items()},
                "efforts": dict(self._robots.efforts),
                "damping": self._robots.own_damping(),
                "wrenches": {n: [f.tolist(), t.tolist()]
                             for n, (_, f, t) in self._robots.wrenches.items()}}

    def _item(self, owner: str) -> dict[str, Any]:
        body = self._bodies[owner]
        if body.model is None:
            return snapformat.body_item(body)
        return snapformat.model_item(body, self._models[owner], self._edits.get(owner, []))

    def restore(self, data: dict[str, Any]) -> None:
        if not isinstance(data, dict) or data.get("format") != snapformat.FORMAT:
            raise InvalidArgumentError(
                f"not a DART snapshot (format {snapformat.FORMAT!r} expected)")
        try:
            self._restore(data)
        except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
            raise InvalidArgumentError(f"malformed DART snapshot: {type(exc).__name__}: "
                                       f"{exc}") from None

    def _restore(self, data: dict[str, Any]) -> None:
        # Bodies of one mesh share its shape, as a spawn group's do: each load takes ms.
        self._loaded_meshes = {}
        self.set_params(check_updates("dart", PARAMS, data["params"]))  # type: ignore[attr-defined]
        for item in data["items"]:
            if item["kind"] == "body":
                self._restore_body(item)
            elif item["kind"] == "model":
                self._restore_model(item)
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

    def _restore_body(self, item: dict[str, Any]) -> None:
        shape, size = str(item["shape"]), tuple(float(s) for s in item["size"])
        static = bool(item["static"])
        mass = math.nan if static else float(item["mass"])
        follows = item["follows"]
        rgba = None if item["rgba"] is None else tuple(float(c) for c in item["rgba"])
        body = spawning.Body(str(item["name"]), shape, size, static, mass,
                          float(item["friction"]), float(item["restitution"]),
                          bool(follows[0]), bool(follows[1]), None, None, rgba,
                          unit_inertia=snapformat.unit_inertia(item.get("unit_inertia"), static))
        self._check_new([body.name])  # type: ignore[attr-defined]
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
        self._add(body)  # type: ignore[attr-defined]

    def _restore_model(self, item: dict[str, Any]) -> None:
        skeletons = models.parse(str(item["fmt"]), str(item["text"]), bool(item["fixed_base"]))
        index = int(item["index"])
        skeleton = skeletons[index]
        prefix = str(item["prefix"])
        self._check_new(models.link_names(skeleton, prefix))  # type: ignore[attr-defined]
        self._add_model(models.Model(  # type: ignore[attr-defined]
            models.root_name(skeleton, prefix), skeleton, str(item["fmt"]), str(item["text"]),
            prefix, bool(item["fixed_base"]), index))
        for name, wire in item["edits"]:
            self._edit(self._bodies[name], BodyProperties(**wire))  # type: ignore[attr-defined]
        count = skeleton.getNumDofs()
        skeleton.setPositions(snapformat.vector(item["positions"], count))
        skeleton.setVelocities(snapformat.vector(item["velocities"], count))
