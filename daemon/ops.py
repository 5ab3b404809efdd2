"""Scene operations: parse a request's args, apply it to the World, build the result map.

Each function takes the World and the request's ``args`` map and returns the ``result``
map of the reply. Parsing happens before anything is changed, so a bad request leaves the
scene as it was.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.world import World
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    FeatureUnsupportedError,
    InvalidArgumentError,
    pack_f64,
)
from galton.protocol.model import (
    MAX_BATCH,
    check_names,
    check_type,
    decode_poses,
    decode_twists,
    require,
)

SceneOp = Callable[[World, dict[str, Any]], dict[str, Any]]
MAX_MODEL_BYTES = 16 * 1024 * 1024


def spawn(world: World, args: dict[str, Any]) -> dict[str, Any]:
    groups_raw = require(args, "groups", list, "spawn")
    if not groups_raw:
        raise InvalidArgumentError("spawn.groups must hold at least one group")
    groups = [BodyGroup.from_wire(g, f"spawn.groups[{i}]") for i, g in enumerate(groups_raw)]
    total = sum(len(g) for g in groups)
    if total > MAX_BATCH:
        raise InvalidArgumentError(f"spawn asks for {total} bodies; at most {MAX_BATCH} a call")
    _require_shapes(world, groups)
    return {"names": world.spawn(groups)}


def _require_shapes(world: World, groups: list[BodyGroup]) -> None:
    supported = world.engine.capabilities().body_shapes
    for group in groups:
        if group.shape not in supported:
            raise FeatureUnsupportedError(
                f"the {world.engine.name} engine cannot spawn a {group.shape}")


def load_model(world: World, args: dict[str, Any]) -> dict[str, Any]:
    fmt = require(args, "format", str, "load_model")
    formats = world.engine.capabilities().model_formats
    if fmt not in formats:
        raise FeatureUnsupportedError(
            f"the {world.engine.name} engine loads {', '.join(formats) or 'no'} models, "
            f"not {fmt!r}")
    text, path = args.get("text"), args.get("path")
    if (text is None) == (path is None):
        raise InvalidArgumentError("load_model needs exactly one of 'text' or 'path'")
    source = check_type(text if text is not None else path, str, "load_model.text/path")
    if len(source) > MAX_MODEL_BYTES:
        raise InvalidArgumentError(f"load_model: the model is over {MAX_MODEL_BYTES} bytes")
    prefix = check_type(args.get("prefix", ""), str, "load_model.prefix")
    return {"names": world.load_model(fmt, text, path, prefix)}


def list_entities(world: World, args: dict[str, Any]) -> dict[str, Any]:
    pattern = args.get("name")
    tag = args.get("tag")
    kind = args.get("kind")
    for key, value in (("name", pattern), ("tag", tag), ("kind", kind)):
        if value is not None:
            check_type(value, str, f"list.{key}")
    found = world.select(pattern, tag, kind)
    return {"entities": [info.to_wire() for info in found]}


def _names_or_all(world: World, args: dict[str, Any], where: str) -> list[str]:
    if args.get("names") is None:
        return list(world.entities)
    return check_names(args["names"], f"{where}.names")


def get_states(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = _names_or_all(world, args, "get_states")
    poses, twists = world.get_states(names)
    return {"names": names, "poses": pack_f64(poses), "twists": pack_f64(twists)}


def set_states(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = check_names(require(args, "names", list, "set_states"), "set_states.names")
    poses_raw, twists_raw = args.get("poses"), args.get("twists")
    if poses_raw is None and twists_raw is None:
        raise InvalidArgumentError("set_states needs 'poses', 'twists' or both")
    poses = None if poses_raw is None else decode_poses(poses_raw, len(names),
                                                        "set_states.poses")
    twists = None if twists_raw is None else decode_twists(twists_raw, len(names),
                                                           "set_states.twists")
    world.set_states(names, poses, twists)
    return {"count": len(names)}


def update(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = check_names(require(args, "names", list, "update"), "update.names")
    props = BodyProperties.from_wire(require(args, "properties", dict, "update"),
                                     "update.properties")
    world.update(names, props)
    return {"count": len(names)}


def delete(world: World, args: dict[str, Any]) -> dict[str, Any]:
    names = check_names(require(args, "names", list, "delete"), "delete.names")
    world.delete(names)
    return {"count": len(names)}


def get_params(world: World, args: dict[str, Any]) -> dict[str, Any]:
    return {"params": _wire_values(world.engine.get_params())}


def set_params(world: World, args: dict[str, Any]) -> dict[str, Any]:
    params = require(args, "params", dict, "set_params")
    world.engine.set_params(params)
    return {"params": _wire_values(world.engine.get_params())}


def capabilities(world: World, args: dict[str, Any]) -> dict[str, Any]:
    caps = world.engine.capabilities()
    caps.engines_available = tuple(ENGINE_CLASSES)
    return caps.to_wire()


def _wire_values(params: dict[str, Any]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}


SCENE_OPS: dict[str, SceneOp] = {
    "spawn": spawn,
    "load_model": load_model,
    "list": list_entities,
    "get_states": get_states,
    "set_states": set_states,
    "update": update,
    "delete": delete,
    "get_params": get_params,
    "set_params": set_params,
    "capabilities": capabilities,
}
# Ops that change the scene: their replies are stamped, and they fault-check nothing.
MUTATING_OPS = frozenset({"spawn", "load_model", "set_states", "update", "delete", "set_params"})
