"""Joint and wrench operations: parse a request, check it whole against the world, apply it.

joints, get_joint_states, set_joint_states, set_joint_targets, apply_wrench and
clear_wrenches (docs/protocol.md). Every check runs before the engine is called, so a
rejected request changes nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.core.reply_limit import reads_size, require_room
from galton.daemon.ops.binding import scene_op
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError, pack_f64
from galton.protocol import requests as rq
from galton.protocol.model import (
    check_names,
    decode_points,
    decode_values,
    decode_wrenches,
)


@scene_op("joints")
def joints(world: World, request: rq.Joints) -> dict[str, Any]:
    model = request.model
    if model is not None:
        world.require_known([model])
    names = request.names
    selected = world.joints.select(
        model, None if names is None else check_names(names, "joints.names"))
    return {"joints": [info.to_wire() for info in selected]}


def joint_states(world: World, names: list[str], where: str) -> dict[str, Any]:
    """The result map of a joint read: names, and packed positions, velocities, efforts."""
    world.joints.require_scalar(names, where)
    world.verify()
    positions, velocities, efforts = world.engine.get_joint_states(names)
    return {"names": names, "positions": pack_f64(positions),
            "velocities": pack_f64(velocities), "efforts": pack_f64(efforts)}


@scene_op("get_joint_states")
def get_joint_states(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    raw = request.names
    names = (world.joints.scalar_names() if raw is None
             else check_names(raw, "get_joint_states.names"))
    return joint_states(world, names, "get_joint_states")


@scene_op("set_joint_states")
def set_joint_states(world: World, request: rq.SetJointStates) -> dict[str, Any]:
    names = check_names(request.names, "set_joint_states.names")
    infos = world.joints.require_scalar(names, "set_joint_states")
    positions = decode_values(request.positions, len(names), "set_joint_states.positions",
                              bound=rq.value_bound(rq.SetJointStates, "positions"))
    raw = request.velocities
    velocities = None if raw is None else decode_values(
        raw, len(names), "set_joint_states.velocities",
        bound=rq.value_bound(rq.SetJointStates, "velocities"))
    world.joints.check_limits(infos, positions, "set_joint_states.positions")
    read = request.read
    if read is not None:
        read = check_names(read, "set_joint_states.read")
        world.require_known(read)
        require_room("this set_joint_states reply's reads", reads_size(read, None),
                     world.limits.max_reply_bytes, "no joint was set; read fewer bodies")
    world.set_joint_states(names, positions, velocities)
    if read is None:
        return {"count": len(names)}
    poses, twists = world.get_states(read)  # the links where the joints put them
    return {"count": len(names), "names": read, "poses": pack_f64(poses),
            "twists": pack_f64(twists)}


@scene_op("set_joint_targets")
def set_joint_targets(world: World, request: rq.SetJointTargets) -> dict[str, Any]:
    names = check_names(request.names, "set_joint_targets.names")
    mode = request.mode  # one of TARGET_MODES: its declaration says so
    count = len(names)
    if mode != "none" and request.targets is None:
        raise InvalidArgumentError(f"a {mode} target needs 'targets' (one per joint)")
    targets = _values(request.targets, "targets", count, 0.0, mode)
    kp = _values(request.kp, "kp", count, 0.0)
    kd = _values(request.kd, "kd", count, 0.0)
    max_effort = _values(request.max_effort, "max_effort", count, np.inf, allow_inf=True)
    world.require_valid()
    world.joints.set_targets(names, mode, targets, kp, kd, max_effort)
    return {"count": count}


def _values(raw: float | bytes | None, key: str, count: int, default: float,
            mode: str | None = None, *, allow_inf: bool = False) -> np.ndarray:
    """A per-joint field, within the bound its declaration gives (a target's: its mode's)."""
    if raw is None:
        return np.full(count, default)
    return decode_values(raw, count, f"set_joint_targets.{key}", allow_inf=allow_inf,
                         bound=rq.value_bound(rq.SetJointTargets, key, mode))


@scene_op("apply_wrench")
def apply_wrench(world: World, request: rq.ApplyWrench) -> dict[str, Any]:
    names = check_names(request.names, "apply_wrench.names")
    world.require_known(names)
    static = [n for n in names if world.entities[n].info.static]
    if static:
        raise InvalidArgumentError(f"apply_wrench: {static[0]!r} is static (or a fixed base): "
                                   "a wrench cannot move it")
    wrenches = decode_wrenches(request.wrenches, len(names), "apply_wrench.wrenches")
    raw_points = request.points
    points = None if raw_points is None else decode_points(raw_points, len(names),
                                                          "apply_wrench.points")
    duration = request.duration
    world.require_valid()
    world.wrenches.apply(world.engine, names, wrenches, points, duration, world.step_index)
    return {"count": len(names)}


@scene_op("clear_wrenches")
def clear_wrenches(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    raw = request.names
    names = None if raw is None else check_names(raw, "clear_wrenches.names")
    if names is not None:
        world.require_known(names)
    world.wrenches.clear(world.engine, names)
    return {"count": len(world.entities) if names is None else len(names)}
