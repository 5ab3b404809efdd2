"""Entity operations (the scene of one World): check a request, apply it, build the result.

Each function takes the World and the operation's typed request (protocol/requests.py,
already checked for types) and returns the ``result`` map of the reply. The remaining
checks happen before anything is changed, so a bad request leaves the scene as it was.
"""

from __future__ import annotations

import fnmatch
import os
import stat
from collections.abc import Callable
from typing import Any

import numpy as np

from galton.daemon.core.calls import Call
from galton.daemon.core.context import CapabilitiesContext
from galton.daemon.core.host_info import host_info
from galton.daemon.core.reply_limit import require_room
from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.engines.base import FEATURE_SPAWN_INERTIA, Shape, ShapeMesh
from galton.daemon.ops.binding import handles, scene_op
from galton.daemon.world.model_files import search_folders
from galton.daemon.world.world import World
from galton.protocol import (
    BodyGroup,
    BodyProperties,
    FeatureUnsupportedError,
    InvalidArgumentError,
    ResourceLimitError,
    pack_f64,
)
from galton.protocol import mesh as mesh_wire
from galton.protocol import requests as rq
from galton.protocol.errors import brief
from galton.protocol.model import (
    check_names,
    check_tags,
    decode_points,
    decode_poses,
    decode_twists,
)
from galton.protocol.operations import GetEntities
from galton.protocol.vocabulary import MAX_BATCH, MODEL_SHAPES

SceneOp = Callable[[World, Any], dict[str, Any]]  # Any: the op's declared request
MAX_PREFIX_LENGTH = 64


@scene_op("spawn")
def spawn(world: World, request: rq.Spawn) -> dict[str, Any]:
    groups_raw = request.groups
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


@scene_op("load_model")
def load_model(world: World, request: rq.LoadModel) -> dict[str, Any]:
    fmt = request.format
    formats = world.engine.capabilities().model_formats
    if fmt not in formats:
        raise FeatureUnsupportedError(
            f"the {world.engine.name} engine loads {', '.join(formats) or 'no'} models, "
            f"not {brief(fmt)}")
    text, path = request.text, request.path
    if (text is None) == (path is None):
        raise InvalidArgumentError("load_model needs exactly one of 'text' or 'path'")
    limit = world.limits.max_model_bytes
    if text is not None:
        if len(text) > limit:
            raise ResourceLimitError(f"load_model.text holds {len(text)} characters; at most "
                                     f"{limit}", {"limit": "max_model_bytes", "max": limit})
    elif path is not None:
        path = model_file(path, limit)
    prefix = check_prefix(request.prefix)
    fixed_base = request.fixed_base
    search = search_folders(request.search_path)
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


def check_prefix(prefix: str) -> str:
    """A name prefix: printable, and short enough that prefixed names stay names."""
    if len(prefix) > MAX_PREFIX_LENGTH or not prefix.isprintable():
        raise InvalidArgumentError(
            f"load_model.prefix {brief(prefix)} must be at most {MAX_PREFIX_LENGTH} printable "
            "characters")
    return prefix


@scene_op("list")
def list_entities(world: World, request: rq.List) -> dict[str, Any]:
    found = world.select(request.name, request.tag, request.kind)
    return {"entities": [info.to_wire() for info in world.effective(found)]}


def _names_or_all(world: World, names: list[str] | None, where: str) -> list[str]:
    if names is None:
        return list(world.entities)
    return check_names(names, f"{where}.names")


@scene_op("get_states")
def get_states(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    names = _names_or_all(world, request.names, "get_states")
    poses, twists = world.get_states(names)
    return {"names": names, "poses": pack_f64(poses), "twists": pack_f64(twists)}


@scene_op("get_bounds")
def get_bounds(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    """Each entity's axis-aligned bounds in the world frame (simulation_interfaces'
    GetEntityBounds): rows of ``min_x min_y min_z max_x max_y max_z``."""
    names = _names_or_all(world, request.names, "get_bounds")
    return {"names": names, "bounds": pack_f64(bounds_of(world, names))}


@scene_op("get_entities")
def get_entities(world: World, request: GetEntities) -> dict[str, Any]:
    """The entities that pass every filter sent (simulation_interfaces' GetEntities): a
    a name the glob ``pattern`` matches (as ``list``'s; GetEntities takes a regex, but
    Python's ``re`` can backtrack without bound on a client's pattern, stalling the physics
    thread), bounds that touch the box ``region``."""
    pattern = request.pattern
    region = _region(request.region) if request.region is not None else None
    names = [name for name in world.entities
             if pattern is None or fnmatch.fnmatchcase(name, pattern)]
    if region is not None and names:
        low, high = region
        rows = bounds_of(world, names)
        touch = np.all((rows[:, :3] <= high) & (rows[:, 3:] >= low), axis=1)
        names = [name for name, inside in zip(names, touch, strict=True) if inside]
    return {"names": names}


def _region(raw: bytes) -> tuple[np.ndarray, np.ndarray]:
    low, high = decode_points(raw, 2, "get_entities.region")
    if (low > high).any():
        raise InvalidArgumentError(
            f"get_entities.region's min corner {low.tolist()} exceeds its max corner "
            f"{high.tolist()} on some axis")
    return low, high


def bounds_of(world: World, names: list[str]) -> np.ndarray:
    """The (n, 6) world-frame bounds of these entities: a primitive's from its shape, a
    model's asked of the engine (FEATURE_UNSUPPORTED where it cannot say)."""
    poses, _ = world.get_states(names)  # unknown names: NOT_FOUND, as get_states
    infos = [world.entities[n].info for n in names]
    modelled = [n for n, info in zip(names, infos, strict=True) if info.shape in MODEL_SHAPES]
    from_engine = dict(zip(modelled, world.engine.bounds(modelled), strict=True)) \
        if modelled else {}
    rows = [from_engine[info.name] if info.name in from_engine
            else primitive_bounds(info.shape, info.size, pose)
            for info, pose in zip(infos, poses, strict=True)]
    return np.array(rows, dtype=float).reshape(-1, 6)


@scene_op("get_shapes")
def get_shapes(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    """Each entity's collision shapes in its own frame: a spawned primitive is its one
    shape at its origin (a spawned mesh with the triangles it was spawned with); a loaded
    model's bodies are asked of the engine, with the triangles of the meshes it keeps."""
    names = _names_or_all(world, request.names, "get_shapes")
    world.get_states(names)  # unknown names: NOT_FOUND, as get_states
    infos = [world.entities[n].info for n in names]
    modelled = [n for n, info in zip(names, infos, strict=True) if info.shape in MODEL_SHAPES]
    from_engine = dict(zip(modelled, world.engine.shapes(modelled), strict=True)) \
        if modelled else {}
    engine_meshes = dict(zip(modelled, world.engine.shape_meshes(modelled), strict=True)) \
        if modelled else {}
    origin = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    shapes: list[list[Shape]] = []
    meshes: list[ShapeMesh | None] = []
    for info in infos:
        if info.name in from_engine:
            shapes.append(from_engine[info.name])
            known = engine_meshes[info.name]
            meshes += [known.get(row) for row in range(len(shapes[-1]))]
        else:
            shapes.append([(info.shape, tuple(info.size), origin)])
            meshes.append(world.entities[info.name].mesh)
    return shapes_reply(names, shapes, meshes, world.limits.max_reply_bytes)


def shapes_reply(names: list[str], shapes: list[list[Shape]], meshes: list[ShapeMesh | None],
                 limit: int) -> dict[str, Any]:
    """get_shapes' result map: flat rows, and where a row is a mesh, each mesh's triangles
    once (refused up front when they would pass ``max_reply_bytes``)."""
    rows = [shape for entity in shapes for shape in entity]
    table: dict[int, int] = {}  # id of a mesh's vertex array -> its index in the reply
    distinct: list[ShapeMesh] = []
    for mesh in meshes:
        if mesh is not None and id(mesh[0]) not in table:
            table[id(mesh[0])] = len(distinct)
            distinct.append(mesh)
    reply_bytes = len(rows) * (10 * 8 + 16) + sum(24 * len(v) + 12 * len(f)
                                                  for v, f in distinct)
    require_room("this get_shapes reply", reply_bytes, limit, "ask for fewer names")
    sizes = [[*size, 0.0, 0.0, 0.0][:3] for _, size, _ in rows]
    kinds = [kind for kind, _, _ in rows]
    result: dict[str, Any] = {
        "names": names, "counts": [len(entity) for entity in shapes], "kinds": kinds,
        "sizes": pack_f64(np.array(sizes, dtype=float).reshape(-1, 3)),
        "poses": pack_f64(np.array([pose for _, _, pose in rows], dtype=float).reshape(-1, 7))}
    if "mesh" in kinds:
        result["meshes"] = [-1 if mesh is None else table[id(mesh[0])] for mesh in meshes]
        result["mesh_vertices"] = [mesh_wire.pack_vertices(v) for v, _ in distinct]
        result["mesh_faces"] = [mesh_wire.pack_faces(f) for _, f in distinct]
    return result


def primitive_bounds(shape: str, size: tuple[float, ...], pose: np.ndarray) -> np.ndarray:
    """The world-frame box around a primitive (half sizes as SIZE_LAYOUT; a cylinder's
    and a capsule's axis is their local z; a plane is a box of no thickness)."""
    x, y, z, w = pose[3], pose[4], pose[5], pose[6]
    rotation = np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    if shape == "sphere":
        half = np.full(3, size[0])
    elif shape in ("cylinder", "capsule"):
        radius, length, axis = size[0], size[1], np.abs(rotation[:, 2])
        across = radius if shape == "capsule" else radius * np.sqrt(np.clip(1 - axis**2, 0, 1))
        half = across + length * axis
    else:  # box, plane, mesh (its size: its vertices' reach about its origin)
        local = np.array([*size[:2], size[2] if len(size) > 2 else 0.0])
        half = np.abs(rotation) @ local
    centre = np.asarray(pose[:3], dtype=float)
    return np.concatenate([centre - half, centre + half])


@scene_op("set_states")
def set_states(world: World, request: rq.SetStates) -> dict[str, Any]:
    names = check_names(request.names, "set_states.names")
    poses_raw, twists_raw = request.poses, request.twists
    if poses_raw is None and twists_raw is None:
        raise InvalidArgumentError("set_states needs 'poses', 'twists' or both")
    poses = None if poses_raw is None else decode_poses(poses_raw, len(names),
                                                        "set_states.poses")
    twists = None if twists_raw is None else decode_twists(twists_raw, len(names),
                                                           "set_states.twists")
    world.set_states(names, poses, twists)
    return {"count": len(names)}


@scene_op("update")
def update(world: World, request: rq.Update) -> dict[str, Any]:
    names = check_names(request.names, "update.names")
    declared = request.properties  # types, ranges and keys checked by its declaration
    rgba = declared.rgba
    props = BodyProperties(
        mass=declared.mass, friction=declared.friction, restitution=declared.restitution,
        rgba=None if rgba is None else (rgba[0], rgba[1], rgba[2], rgba[3]),
        tags=None if declared.tags is None else check_tags(declared.tags,
                                                           "update.properties.tags"))
    world.update(names, props)
    return {"count": len(names)}


@scene_op("delete")
def delete(world: World, request: rq.NamedOnly) -> dict[str, Any]:
    names = check_names(request.names, "delete.names")
    world.delete(names)
    return {"count": len(names)}


@scene_op("get_params")
def get_params(world: World, request: rq.NoArgs) -> dict[str, Any]:
    return {"params": _wire_values(world.engine.get_params())}


@scene_op("set_params")
def set_params(world: World, request: rq.SetParams) -> dict[str, Any]:
    world.set_params(request.params)
    return {"params": _wire_values(world.engine.get_params())}


@handles("capabilities")
def capabilities(ctx: CapabilitiesContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    """The engine's capabilities, with what the daemon adds (its fronts' endpoints)."""
    caps = ctx.world_for(request).engine.capabilities()
    caps.engines_available = tuple(ENGINE_CLASSES)
    caps.host = host_info()
    return {**caps.to_wire(), **ctx.advertised}


def _wire_values(params: dict[str, Any]) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()}
