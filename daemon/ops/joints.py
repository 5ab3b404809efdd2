"""Joint and wrench operations: parse a request, check it whole against the world, apply it.

joints, get_joint_states, set_joint_states, set_joint_targets, apply_wrench and
clear_wrenches (docs/protocol.md). Every check runs before the engine is called, so a
rejected request changes nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.world.scene import World
from galton.protocol import TARGET_MODES, InvalidArgumentError, pack_f64
from galton.protocol.errors import brief, did_you_mean
from galton.protocol.model import (
    check_names,
    check_type,
    decode_points,
    decode_values,
    decode_wrenches,
    finite_number,
    require,
)


def joints(world: World, args: dict[str, Any]) -> dict[str, Any]:
    model = args.get("model")
    if model is not None:
        check_type(model, str, "joints.model")
        world.require_known([model])
    names = args.get("names")
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


def get_joint_states(world: World, args: dict[str, Any]) -> dict[str, Any]:
    raw = args.get("names")
    names = (world.joints.scalar_names() if raw is None
             else check_names(raw, "get_joint_states.names"))
    return joint_states(world, names, "get_joint_states")


def set_joint_states(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = check_names(require(args, "names", list, "set_joint_states"),
                        "set_joint_states.names")
    infos = world.joints.require_scalar(names, "set_joint_states")
    positions = decode_values(args.get("positions"), len(names), "set_joint_states.positions")
    raw = args.get("velocities")
    velocities = None if raw is None else decode_values(raw, len(names),
                                                        "set_joint_states.velocities")
    world.joints.check_limits(infos, positions, "set_joint_states.positions")
    read = args.get("read")
    if read is not None:
        read = check_names(read, "set_joint_states.read")
        world.require_known(read)
    world.set_joint_states(names, positions, velocities)
    if read is None:
        return {"count": len(names)}
    poses, twists = world.get_states(read)  # the links where the joints put them
    return {"count": len(names), "names": read, "poses": pack_f64(poses),
            "twists": pack_f64(twists)}


def set_joint_targets(world: World, args: dict[str, Any]) -> dict[str, Any]:
    where = "set_joint_targets"
    names = check_names(require(args, "names", list, where), f"{where}.names")
    mode = require(args, "mode", str, where)
    if mode not in TARGET_MODES:
        raise InvalidArgumentError(f"{where}.mode {brief(mode)} is not one of "
                                   f"{', '.join(TARGET_MODES)}{did_you_mean(mode, TARGET_MODES)}")
    count = len(names)
    if mode != "none" and args.get("targets") is None:
        raise InvalidArgumentError(f"a {mode} target needs 'targets' (one per joint)")
    targets = _values(args, "targets", count, 0.0)
    kp, kd = _values(args, "kp", count, 0.0), _values(args, "kd", count, 0.0)
    max_effort = _values(args, "max_effort", count, np.inf, allow_inf=True)
    world.require_valid()
    world.joints.set_targets(names, mode, targets, kp, kd, max_effort)
    return {"count": count}


def _values(args: dict[str, Any], key: str, count: int, default: float, *,
            allow_inf: bool = False) -> np.ndarray:
    raw = args.get(key)
    if raw is None:
        return np.full(count, default)
    return decode_values(raw, count, f"set_joint_targets.{key}", allow_inf=allow_inf)


def apply_wrench(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = check_names(require(args, "names", list, "apply_wrench"), "apply_wrench.names")
    world.require_known(names)
    static = [n for n in names if world.entities[n].info.static]
    if static:
        raise InvalidArgumentError(f"apply_wrench: {static[0]!r} is static (or a fixed base): "
                                   "a wrench cannot move it")
    wrenches = decode_wrenches(args.get("wrenches"), len(names), "apply_wrench.wrenches")
    raw_points = args.get("points")
    points = None if raw_points is None else decode_points(raw_points, len(names),
                                                          "apply_wrench.points")
    raw_duration = args.get("duration")
    duration = None if raw_duration is None else finite_number(
        raw_duration, "apply_wrench.duration", low=0.0, low_open=True)
    world.require_valid()
    world.wrenches.apply(world.engine, names, wrenches, points, duration, world.step_index)
    return {"count": len(names)}


def clear_wrenches(world: World, args: dict[str, Any]) -> dict[str, Any]:
    raw = args.get("names")
    names = None if raw is None else check_names(raw, "clear_wrenches.names")
    if names is not None:
        world.require_known(names)
    world.wrenches.clear(world.engine, names)
    return {"count": len(world.entities) if names is None else len(names)}
