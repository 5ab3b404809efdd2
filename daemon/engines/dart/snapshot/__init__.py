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
"""

from __future__ import annotations

import importlib.metadata
import math
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.base import Target
from galton.daemon.engines.dart import meshes, models
from galton.daemon.engines.dart import spawn as spawning
from galton.daemon.engines.dart.params import PARAMS
from galton.daemon.engines.dart.snapshot import format as snapformat
from galton.daemon.engines.params import check_updates
from galton.protocol import BodyProperties, InvalidArgumentError
from galton.protocol import mesh as mesh_wire
from galton.protocol.errors import brief
from galton.protocol.model import WRENCH_BOUNDS, check_name, check_rows, decode_values
from galton.protocol.vocabulary import (
    MAX_EFFORT,
    MAX_GAIN,
    MAX_JOINT_POSITION,
    MAX_JOINT_SPEED,
)

# A target's bound is its mode's quantity, as set_joint_targets bounds it.
TARGET_BOUNDS = {"none": MAX_JOINT_POSITION, "position": MAX_JOINT_POSITION,
                 "velocity": MAX_JOINT_SPEED, "effort": MAX_EFFORT}

if TYPE_CHECKING:
    from galton.daemon.engines.dart.engine import DartEngine


def snapshot(engine: DartEngine, *, canonical: bool = True) -> dict[str, Any]:
    if canonical:
        engine._rebuild()
    return {"format": snapformat.FORMAT, "engine": "dart",
            "dartpy": importlib.metadata.version("dartpy"),
            "params": {k: list(v) if isinstance(v, tuple) else v
                       for k, v in engine._values.items()},
            "time": float(engine._world.getTime()),
            "items": [_item(engine, owner) for owner in engine._owners],
            "targets": {n: [t.mode, t.target, t.kp, t.kd, t.max_effort]
                        for n, t in engine._robots.targets.items()},
            "efforts": dict(engine._robots.efforts),
            "damping": engine._robots.own_damping(),
            "wrenches": {n: [f.tolist(), t.tolist()]
                         for n, (_, f, t) in engine._robots.wrenches.items()}}


def _item(engine: DartEngine, owner: str) -> dict[str, Any]:
    body = engine._bodies[owner]
    if body.model is None:
        return snapformat.body_item(body)
    return snapformat.model_item(body, engine._models[owner], engine._edits.get(owner, []))


def restore(engine: DartEngine, data: dict[str, Any]) -> None:
    if not isinstance(data, dict) or data.get("format") != snapformat.FORMAT:
        raise InvalidArgumentError(
            f"not a DART snapshot (format {snapformat.FORMAT!r} expected)")
    try:
        _restore(engine, data)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise InvalidArgumentError(f"malformed DART snapshot: {type(exc).__name__}: "
                                   f"{exc}") from None


def _restore(engine: DartEngine, data: dict[str, Any]) -> None:
    # Bodies of one mesh share its shape, as a spawn group's do: each load takes ms.
    engine._loaded_meshes = {}
    engine.set_params(check_updates("dart", PARAMS, data["params"]))
    for item in data["items"]:
        if item["kind"] == "body":
            _restore_body(engine, item)
        elif item["kind"] == "model":
            _restore_model(engine, item)
        else:
            raise ValueError(f"unknown item kind {item['kind']!r}")
    engine._world.setTime(float(data["time"]))
    for name, (mode, target, kp, kd, effort) in data["targets"].items():
        engine._robots.scalar([name])
        engine._robots.targets[name] = _target(name, mode, target, kp, kd, effort)
    engine._robots.efforts.update({str(k): float(v) for k, v in data["efforts"].items()})
    engine._robots.put_back_damping(data.get("damping", {}))
    for name, (force, torque) in data["wrenches"].items():
        pair = np.concatenate([snapformat.vector(force), snapformat.vector(torque)])
        wrench = check_rows(pair[None], 1, 6, f"the snapshot's wrench on {name!r}",
                            WRENCH_BOUNDS)[0]
        engine._robots.wrenches[name] = (engine._bodies[name].node, wrench[:3], wrench[3:])


def _restore_body(engine: DartEngine, item: dict[str, Any]) -> None:
    shape, size = str(item["shape"]), tuple(float(s) for s in item["size"])
    static = bool(item["static"])
    mass = math.nan if static else float(item["mass"])
    follows = item["follows"]
    rgba = None if item["rgba"] is None else tuple(float(c) for c in item["rgba"])
    name = check_name(item["name"], "the snapshot's body name")
    body = spawning.Body(name, shape, size, static, mass,
                      float(item["friction"]), float(item["restitution"]),
                      bool(follows[0]), bool(follows[1]), None, None, rgba,
                      unit_inertia=snapformat.unit_inertia(item.get("unit_inertia"), static))
    engine._check_new([body.name])
    if shape not in ("sphere", "box", "cylinder", "capsule", "plane", "mesh"):
        raise ValueError(f"unknown shape {shape!r}")
    if shape == "mesh":
        where = f"the snapshot's mesh {body.name!r}"
        vertices = mesh_wire.decode_vertices(item["vertices"], f"{where} vertices")
        faces = mesh_wire.decode_faces(item["faces"], len(vertices), f"{where} faces")
        mesh_wire.check_area(vertices, faces, where)
        key = (bytes(item["vertices"]), bytes(item["faces"]))
        if key not in engine._loaded_meshes:
            engine._loaded_meshes[key] = meshes.mesh_shape(vertices, faces)
        body.mesh, body.mesh_shape = (vertices, faces), engine._loaded_meshes[key]
    elif item.get("vertices") is not None or item.get("faces") is not None:
        raise ValueError(f"a {shape} has no vertices or faces")
    spawning.build(body, snapformat.vector(item["positions"], 6),
                   snapformat.vector(item["velocities"], 6))
    engine._add(body)


def _restore_model(engine: DartEngine, item: dict[str, Any]) -> None:
    skeletons = models.parse(str(item["fmt"]), str(item["text"]), bool(item["fixed_base"]))
    index = int(item["index"])
    skeleton = skeletons[index]
    prefix = str(item["prefix"])
    engine._check_new(models.link_names(skeleton, prefix))
    engine._add_model(models.Model(
        models.root_name(skeleton, prefix), skeleton, str(item["fmt"]), str(item["text"]),
        prefix, bool(item["fixed_base"]), index))
    for name, wire in item["edits"]:
        engine._edit(engine._bodies[name], BodyProperties(**wire))
    count = skeleton.getNumDofs()
    skeleton.setPositions(snapformat.vector(item["positions"], count))
    skeleton.setVelocities(snapformat.vector(item["velocities"], count))


def _target(name: str, mode: Any, target: Any, kp: Any, kd: Any, effort: Any) -> Target:
    """A held target, within the bounds ``set_joint_targets`` checks (issue 46): DART's
    own format holds it, so its restore checks it, with the protocol's constants."""
    where = f"the snapshot's target of joint {name!r}"
    if mode not in TARGET_BOUNDS:
        raise InvalidArgumentError(f"{where} has mode {brief(mode)}; one of "
                                   f"{', '.join(TARGET_BOUNDS)} expected")
    return Target(mode, *(float(decode_values(value, 1, f"{where}.{key}", bound=bound,
                                              allow_inf=key == "max_effort")[0])
                          for key, value, bound in (
                              ("target", target, TARGET_BOUNDS[mode]), ("kp", kp, MAX_GAIN),
                              ("kd", kd, MAX_GAIN), ("max_effort", effort, MAX_EFFORT))))
