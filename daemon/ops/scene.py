"""Scene operations: parse a request's args, apply it to the World, build the result map.

Each function takes the World and the request's ``args`` map and returns the ``result``
map of the reply. Parsing happens before anything is changed, so a bad request leaves the
scene as it was.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Callable
from typing import Any

from galton.daemon.core.host_info import host_info
from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.engines.base import FEATURE_SPAWN_INERTIA
from galton.daemon.world.model_files import search_folders
from galton.daemon.world.scene import World
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    FeatureUnsupportedError,
    InvalidArgumentError,
    ResourceLimitError,
    pack_f64,
)
from galton.protocol.errors import brief
from galton.protocol.model import check_names, check_type, decode_poses, decode_twists, require
from galton.protocol.vocabulary import MAX_BATCH

SceneOp = Callable[[World, dict[str, Any]], dict[str, Any]]
MAX_PREFIX_LENGTH = 64


def spawn(world: World, args: dict[str, Any]) -> dict[str, Any]:
    groups_raw = require(args, "groups", list, "spawn")
    if not groups_raw:
        raise InvalidArgumentError("spawn.groups must hold at least one group")
    if len(groups_raw) > MAX_BATCH:
        raise InvalidArgumentError(f"spawn holds {len(groups_raw)} groups; at most {MAX_BATCH}")
    groups = [BodyGroup.from_wire(g, f"spawn.groups[{i}]") for i, g in enumerate(groups_raw)]
    total = sum(len(g) for g in groups)
    if total > MAX_BATCH:
        raise InvalidArgumentError(f"spawn asks for {total} bodies; at most {MAX_BATCH} a call")
    world.require_room(total)
    _require_shapes(world, groups)
    return {"names": world.spawn(groups)}


def _require_shapes(world: World, groups: list[BodyGroup]) -> None:
    caps = world.engine.capabilities()
    for group in groups:
        if group.shape not in caps.body_shapes:
            raise FeatureUnsupportedError(
                f"the {world.engine.name} engine cannot spawn a {group.shape}")
        if group.inertia is not None and not caps.supports(FEATURE_SPAWN_INERTIA):
            raise FeatureUnsupportedError(
                f"the {world.engine.name} engine cannot set a spawned body's inertia")


def load_model(world: World, args: dict[str, Any]) -> dict[str, Any]:
    fmt = require(args, "format", str, "load_model")
    formats = world.engine.capabilities().model_formats
    if fmt not in formats:
        raise FeatureUnsupportedError(
            f"the {world.engine.name} engine loads {', '.join(formats) or 'no'} models, "
            f"not {brief(fmt)}")
    text, path = args.get("text"), args.get("path")
    if (text is None) == (path is None):
        raise InvalidArgumentError("load_model needs exactly one of 'text' or 'path'")
    limit = world.limits.max_model_bytes
    if text is not None:
        check_type(text, str, "load_model.text")
        if len(text) > limit:
            raise ResourceLimitError(f"load_model.text holds {len(text)} characters; at most "
                                     f"{limit}", {"limit": "max_model_bytes", "max": limit})
    else:
        path = model_file(check_type(path, str, "load_model.path"), limit)
    prefix = check_prefix(args.get("prefix", ""))
    fixed_base = check_type(args.get("fixed_base", True), bool, "load_model.fixed_base")
    raw_search = args.get("search_path")
    search = search_folders(None if raw_search is None else check_type(
        raw_search, str, "load_model.search_path"))
    world.require_room(1)
    return {"names": world.load_model(fmt, text, path, prefix, fixed_base=fixed_base,
                                      search=search)}


def model_file(path: str, limit: int) -> str:
    """A load_model path must name a regular file of at most ``limit`` bytes: a device, a
    pipe or a folder would block or exhaust the physics thread (``/dev/stdin``,
    ``/dev/zero``)."""
    if not path or "\x00" in path:
        raise InvalidArgumentError(f"load_model.path {brief(path)} is not a file path")
    try:
        info = os.stat(path)
    except OSError as exc:
        raise InvalidArgumentError(
            f"load_model.path {brief(path)} cannot be read: {exc.strerror}") from exc
    if not stat.S_ISREG(info.st_mode):
        raise InvalidArgumentError(f"load_model.path {brief(path)} is not a regular file")
    if info.st_size > limit:
        raise ResourceLimitError(f"load_model.path {brief(path)} holds {info.st_size} bytes; "
                                 f"at most {limit}", {"limit": "max_model_bytes", "max": limit})
    return path


def check_prefix(value: Any) -> str:
    """A name prefix: printable, and short enough that prefixed names stay names."""
    prefix = check_type(value, str, "load_model.prefix")
    if len(prefix) > MAX_PREFIX_LENGTH or not prefix.isprintable():
        raise InvalidArgumentError(
            f"load_model.prefix {brief(prefix)} must be at most {MAX_PREFIX_LENGTH} printable "
            "characters")
    return prefix


def list_entities(world: World, args: dict[str, Any]) -> dict[str, Any]:
    pattern = args.get("name")
    tag = args.get("tag")
    kind = args.get("kind")
    for key, value in (("name", pattern), ("tag", tag), ("kind", kind)):
        if value is not None:
            check_type(value, str, f"list.{key}")
    found = world.select(pattern, tag, kind)
    return {"entities": [info.to_wire() for info in world.effective(found)]}


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
    caps.host = host_info()
    return caps.to_wire()


def _wire_values(params: dict[str, Any]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}

