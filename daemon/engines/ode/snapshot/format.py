"""Snapshots of the ODE world as plain data, and their checks on the way back in.

A moving body's 28 state doubles are stored as read and written back into ODE's memory as
they were, so a restored body starts bit for bit where its source stood (``dBodySet-
Quaternion`` would normalise the quaternion again and could change its last bits). What ODE
keeps besides is each body's sleep flag and its idle counters: the flag is stored; the
counters cannot be read, so a snapshot first restarts them in its source (``canonical``) or
the restore goes on as the source would after ``reset_dynamics``, which restarts them too.
Contact joints live one step and ``dWorldStep`` keeps no warm start: nothing else to carry.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from galton.daemon.engines.ode.native import AVEL, LVEL, POS, QUAT, ROT, STATE_LENGTH
from galton.daemon.engines.ode.spawn import Body
from galton.protocol import BODY_SHAPES, TARGET_MODES, InvalidArgumentError
from galton.protocol import mesh as mesh_wire
from galton.protocol.vocabulary import (
    MAX_COORDINATE,
    MAX_EFFORT,
    MAX_FORCE,
    MAX_GAIN,
    MAX_TORQUE,
    MAX_TWIST,
    QUATERNION_NORM_BAND,
)

# How far a stored quaternion's norm may be from 1, and a rotation matrix's entries from
# [-1, 1]: ODE stores them unit; a re-sealed body holding a zero or huge one would abort the
# process (dxNormalize4) at the next step (issue 46).
UNIT_TOLERANCE = 1e-6

FORMAT = "galton-ode-snapshot"
VERSION = 1


def body_data(body: Body, enabled: bool, wrench: list[float] | None) -> dict[str, Any]:
    return {"name": body.name, "shape": body.shape, "size": list(body.size),
            "static": body.static, "mass": None if body.static else body.mass,
            "friction": body.friction, "restitution": body.restitution,
            "follows": [body.follows_friction, body.follows_restitution],
            "rgba": None if body.rgba is None else list(body.rgba),
            "pose": list(body.pose), "state": [] if body.static else body.state.tolist(),
            "enabled": enabled, "wrench": wrench,
            "unit_inertia": None if body.unit_inertia is None else list(body.unit_inertia),
            "vertices": None if body.mesh is None else mesh_wire.pack_vertices(
                body.mesh.vertices),
            "faces": None if body.mesh is None else mesh_wire.pack_faces(body.mesh.indices)}


def mesh_of(body: dict[str, Any], where: str) -> tuple[np.ndarray, np.ndarray] | None:
    """A mesh body's vertices and faces, checked as spawn checks them; none for the rest."""
    if body["shape"] != "mesh":
        if body.get("vertices") is not None or body.get("faces") is not None:
            raise _fail(where, "has vertices or faces but is no mesh")
        return None
    vertices = mesh_wire.decode_vertices(body.get("vertices"), f"{where}.vertices")
    faces = mesh_wire.decode_faces(body.get("faces"), len(vertices), f"{where}.faces")
    mesh_wire.check_area(vertices, faces, where)
    return vertices, faces


def _fail(where: str, what: str) -> InvalidArgumentError:
    return InvalidArgumentError(f"not an ode snapshot: {where} {what}")


def _numbers(value: Any, length: int, where: str) -> list[float]:
    if not isinstance(value, list) or len(value) != length or not all(
            isinstance(v, float | int) and not isinstance(v, bool) for v in value):
        raise _fail(where, f"must be a list of {length} numbers")
    return [float(v) for v in value]


def check(data: Any) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The snapshot's parameters and bodies, every field checked; InvalidArgumentError
    naming the first bad one."""
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InvalidArgumentError(f"not an ode snapshot (format must be {FORMAT!r})")
    if data.get("version") != VERSION:
        raise _fail("version", f"must be {VERSION}")
    params, bodies = data.get("params"), data.get("bodies")
    if not isinstance(params, dict):
        raise _fail("params", "must be a map")
    if not isinstance(bodies, list):
        raise _fail("bodies", "must be a list")
    names: set[str] = set()
    for k, body in enumerate(bodies):
        if isinstance(body, dict) and "model" in body:
            check_model(body, f"bodies[{k}]")
            continue
        _check_body(body, f"bodies[{k}]")
        if body["name"] in names:
            raise _fail(f"bodies[{k}].name", "repeats another body's")
        names.add(body["name"])
    return params, bodies


def _check_body(body: Any, where: str) -> None:
    if not isinstance(body, dict):
        raise _fail(where, "must be a map")
    if not isinstance(body.get("name"), str) or not body["name"]:
        raise _fail(f"{where}.name", "must be a non-empty string")
    if body.get("shape") not in BODY_SHAPES:
        raise _fail(f"{where}.shape", f"must be one of {BODY_SHAPES}")
    size = body.get("size")
    if not isinstance(size, list) or not 1 <= len(size) <= 3:
        raise _fail(f"{where}.size", "must be a list of 1 to 3 numbers")
    if not all(v > 0 and math.isfinite(v) for v in _numbers(size, len(size), f"{where}.size")):
        raise _fail(f"{where}.size", "must be positive")
    if not isinstance(body.get("static"), bool) or not isinstance(body.get("enabled"), bool):
        raise _fail(where, "static and enabled must be true or false")
    for key in ("friction", "restitution"):
        value = _numbers([body.get(key)], 1, f"{where}.{key}")[0]
        if not 0 <= value <= 100:
            raise _fail(f"{where}.{key}", "must be within 0..100")
    follows = body.get("follows")
    if not isinstance(follows, list) or len(follows) != 2 or not all(
            isinstance(f, bool) for f in follows):
        raise _fail(f"{where}.follows", "must be two booleans")
    if body.get("rgba") is not None:
        _numbers(body["rgba"], 4, f"{where}.rgba")
    if body["static"]:
        _numbers(body.get("pose"), 7, f"{where}.pose")
    else:
        mass = _numbers([body.get("mass")], 1, f"{where}.mass")[0]
        if not (mass > 0 and math.isfinite(mass)):
            raise _fail(f"{where}.mass", "must be positive")
        _check_state(_numbers(body.get("state"), STATE_LENGTH, f"{where}.state"),
                     f"{where}.state")
    if body["static"]:
        _check_quaternion(_numbers(body.get("pose"), 7, f"{where}.pose")[3:], f"{where}.pose")
    if body.get("wrench") is not None:
        _check_wrench(_numbers(body["wrench"], 6, f"{where}.wrench"), f"{where}.wrench")
    if body.get("unit_inertia") is not None and (body["static"] or not all(
            v > 0 and math.isfinite(v)
            for v in _numbers(body["unit_inertia"], 3, f"{where}.unit_inertia"))):
        raise _fail(f"{where}.unit_inertia", "must be 3 positive numbers, on a moving body")
    mesh_of(body, where)


JOINT_FIELDS = ("target", "kp", "kd", "max_effort", "effort")


def model_data(source: dict[str, Any], links: list[dict[str, Any]],
               joints: list[dict[str, Any]]) -> dict[str, Any]:
    """A loaded model: how it was loaded, then its links' states and its joints' targets."""
    return {"model": dict(source), "links": links, "joints": joints}


def check_model(entry: Any, where: str) -> None:
    source = entry.get("model")
    if not isinstance(source, dict) or not isinstance(source.get("prefix"), str) or \
            not isinstance(source.get("fixed_base"), bool) or not all(
                source.get(k) is None or isinstance(source.get(k), str)
                for k in ("text", "path")):
        raise _fail(f"{where}.model", "must say text or path, prefix and fixed_base")
    links, joints = entry.get("links"), entry.get("joints")
    if not isinstance(links, list) or not isinstance(joints, list):
        raise _fail(where, "must hold lists of links and joints")
    for k, link in enumerate(links):
        if not isinstance(link, dict) or not isinstance(link.get("name"), str) or \
                not isinstance(link.get("enabled"), bool):
            raise _fail(f"{where}.links[{k}]", "must name the link and its sleep flag")
        _check_state(_numbers(link.get("state"), STATE_LENGTH, f"{where}.links[{k}].state"),
                     f"{where}.links[{k}].state")
        for key in ("friction", "restitution"):
            _numbers([link.get(key)], 1, f"{where}.links[{k}].{key}")
        if link.get("wrench") is not None:
            _check_wrench(_numbers(link["wrench"], 6, f"{where}.links[{k}].wrench"),
                          f"{where}.links[{k}].wrench")
        follows = link.get("follows")
        if not isinstance(follows, list) or len(follows) != 2 or not all(
                isinstance(f, bool) for f in follows):
            raise _fail(f"{where}.links[{k}].follows", "must be two booleans")
    for k, joint in enumerate(joints):
        if not isinstance(joint, dict) or not isinstance(joint.get("name"), str) or \
                joint.get("mode") not in TARGET_MODES:
            raise _fail(f"{where}.joints[{k}]", "must name the joint and its mode")
        values = _numbers([joint.get(f) for f in JOINT_FIELDS], len(JOINT_FIELDS),
                          f"{where}.joints[{k}]")
        _check_joint(dict(zip(JOINT_FIELDS, values, strict=True)), f"{where}.joints[{k}]")


def _check_state(state: list[float], where: str) -> None:
    """A moving body's 28 doubles as ODE could hold them: finite, within the protocol's
    bounds, a unit quaternion and a rotation matrix's entries."""
    values = np.array(state)
    if not np.isfinite(values).all():
        raise _fail(where, "holds NaN or infinity")
    bounds = ((POS, POS + 3, MAX_COORDINATE), (ROT, ROT + 12, 1.0 + UNIT_TOLERANCE),
              (LVEL, LVEL + 3, MAX_TWIST), (AVEL, AVEL + 3, MAX_TWIST))
    for start, stop, bound in bounds:
        if (np.abs(values[start:stop]) > bound).any():
            raise _fail(where, f"holds a value past {bound:g} in doubles {start}..{stop - 1}")
    norm = math.hypot(*values[QUAT:QUAT + 4])  # scaled: no overflow on a 1e155 component
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        raise _fail(where, f"holds a quaternion of norm {norm:g}, not a unit one")


def _check_quaternion(quaternion: list[float], where: str) -> None:
    low, high = QUATERNION_NORM_BAND
    norm = math.hypot(*quaternion)  # scaled: no overflow on a 1e155 component
    if not (math.isfinite(norm) and low <= norm <= high):
        raise _fail(where, f"holds a quaternion of norm {norm:g}, outside [{low:g}, {high:g}]")


def _check_wrench(wrench: list[float], where: str) -> None:
    if not all(math.isfinite(v) for v in wrench) or \
            max(map(abs, wrench[:3])) > MAX_FORCE or max(map(abs, wrench[3:])) > MAX_TORQUE:
        raise _fail(where, f"must be finite, forces within {MAX_FORCE:g} N and torques "
                           f"within {MAX_TORQUE:g} N m")


def _check_joint(joint: dict[str, float], where: str) -> None:
    """A joint's target, gains and efforts: finite (max_effort may be +inf: no cap) and
    within the protocol's bounds, as set_joint_targets checks them."""
    for key, value in joint.items():
        bound = MAX_GAIN if key in ("kp", "kd") else MAX_EFFORT if key != "target" else \
            max(MAX_EFFORT, MAX_COORDINATE)
        uncapped = key == "max_effort" and value == math.inf
        if not uncapped and not (math.isfinite(value) and abs(value) <= bound):
            raise _fail(f"{where}.{key}", f"must be finite and within {bound:g}")
