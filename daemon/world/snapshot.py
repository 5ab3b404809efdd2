"""A world as bytes: the engine's own snapshot and the World's registry (entities with the
states they were created in, joint modes, held wrenches, the clock), in msgpack.

Never pickle: a client sends snapshots back, and a blob must not be able to run code. A
blob is untrusted input, checked field by field; a world is rebuilt from it on a fresh
engine, so a refused blob leaves every world as it was.
"""

from __future__ import annotations

import dataclasses
import hashlib
from collections.abc import Callable
from typing import Any

import msgpack
import numpy as np

from galton.daemon.core.limits import Limits
from galton.daemon.engines.base import Engine
from galton.daemon.world import snapshot_checks as checks
from galton.daemon.world.world import Entity, Mesh, World, frozen_mesh
from galton.protocol import (
    POSE_WIDTH,
    TARGET_MODES,
    TWIST_WIDTH,
    EntityInfo,
    InvalidArgumentError,
    RemoteError,
    pack_f64,
    unpack_f64,
)
from galton.protocol import mesh as mesh_wire
from galton.protocol.errors import brief

FORMAT = 1


def snapshot_of(world: World, *, canonical: bool = True) -> dict[str, Any]:
    """The world as plain data (the engine's part from ``Engine.snapshot``; ``canonical``
    as there: False never disturbs the world, for checkpoints)."""
    return {"format": FORMAT, "engine": world.engine.name,
            "engine_state": world.engine.snapshot(canonical=canonical), **registry_of(world)}


def clone_of(world: World, name: str, limits: Limits) -> World:
    """A copy of the world in this process (``Engine.clone``), for forks and predictions:
    the source is never disturbed."""
    engine = world.engine.clone()
    try:
        twin = World(engine, name, limits)
        _copy_registry(world, twin)
    except Exception:
        engine.close()
        raise
    return twin


def _copy_registry(world: World, twin: World) -> None:
    """The World's own part, copied object by object (no round trip through the wire: it
    cost a fork milliseconds on 100 bodies); the twin shares the source's structure."""
    twin.entities = {name: Entity(e.info, e.initial_pose, e.initial_twist, e.mesh)
                     for name, e in world.entities.items()}  # infos and arrays never edited
    twin.layout += 1
    twin.step_index, twin._time_base = world.step_index, world._time_base
    twin.verified_step, twin.teleported = world.verified_step, world.teleported
    twin.joints.by_name = dict(world.joints.by_name)
    twin.wrenches.ends = dict(world.wrenches.ends)
    twin.structure = world.structure


def registry_of(world: World) -> dict[str, Any]:
    """The World's own part of a snapshot: entities, joint modes, wrenches, the clock."""
    entities = list(world.entities.values())
    meshes = _meshes_of(entities)
    return {
        **({"meshes": meshes} if meshes else {}),
        "entities": [e.info.to_wire() for e in entities],
        "initial_poses": pack_f64(np.array([e.initial_pose for e in entities]).reshape(
            -1, POSE_WIDTH)),
        "initial_twists": pack_f64(np.array([e.initial_twist for e in entities]).reshape(
            -1, TWIST_WIDTH)),
        "joint_modes": {n: j.mode for n, j in world.joints.by_name.items() if j.mode != "none"},
        "wrench_ends": dict(world.wrenches.ends),
        "clock": {"step": world.step_index, "base_step": world._time_base[0],
                  "base_time": world._time_base[1], "base_dt": world._time_base[2]},
    }


def _meshes_of(entities: list[Entity]) -> list[dict[str, Any]]:
    """The spawned meshes' triangles, once per mesh with the names of its bodies."""
    by_mesh: dict[int, tuple[Mesh, list[str]]] = {}
    for entity in entities:
        if entity.mesh is not None:
            by_mesh.setdefault(id(entity.mesh), (entity.mesh, []))[1].append(entity.info.name)
    return [{"names": names, "vertices": mesh_wire.pack_vertices(mesh[0]),
             "faces": mesh_wire.pack_faces(mesh[1])} for mesh, names in by_mesh.values()]


def encode(data: dict[str, Any], key: bytes | None = None) -> bytes:
    """The blob: the snapshot in msgpack, wrapped with its BLAKE2b digest, so that a blob
    damaged anywhere (a flipped bit in a number included) is refused, not restored as
    another state. With ``key`` (galton-daemon --snapshot-key) the digest is keyed: only a
    daemon holding the key can seal a blob another one accepts."""
    body = msgpack.packb(data, use_bin_type=True)
    seal = "blake2b" if key is None else "keyed_blake2b"
    blob: bytes = msgpack.packb({"galton_snapshot": FORMAT, seal: _digest(body, key),
                                 "body": body}, use_bin_type=True)
    return blob


def _digest(body: bytes, key: bytes | None = None) -> bytes:
    return hashlib.blake2b(body, digest_size=32, key=key or b"").digest()


def decode(blob: Any, limits: Limits, key: bytes | None = None) -> dict[str, Any]:
    """A snapshot blob's data, or InvalidArgumentError saying why it is not one (``key``:
    the daemon's --snapshot-key; blobs must then be sealed with it)."""
    if not isinstance(blob, bytes | bytearray):
        raise InvalidArgumentError(f"restore.blob must be msgpack bin, got {brief(blob)}")
    outer = _unpack(bytes(blob), limits)
    if not isinstance(outer, dict) or outer.get("galton_snapshot") != FORMAT:
        raise InvalidArgumentError(f"restore.blob is not a snapshot of format {FORMAT}")
    body = _sealed_body(outer, key)
    data = _unpack(body, limits)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise InvalidArgumentError(f"restore.blob holds no snapshot of format {FORMAT}")
    return data


def _sealed_body(outer: dict[Any, Any], key: bytes | None) -> bytes:
    """The blob's body once its seal matches (keyed with this daemon's key, if it has one)."""
    body = outer.get("body")
    keyed = "keyed_blake2b" in outer
    if key is not None and not keyed:
        raise InvalidArgumentError("restore.blob is not sealed with this daemon's "
                                   "--snapshot-key: it takes only blobs its key sealed")
    if key is None and keyed:
        raise InvalidArgumentError("restore.blob is sealed with a --snapshot-key; this daemon "
                                   "has none (start it with the same key)")
    seal = outer.get("keyed_blake2b" if keyed else "blake2b")
    if not isinstance(body, bytes) or seal != _digest(body, key):
        raise InvalidArgumentError("restore.blob is corrupt, or sealed with another key: its "
                                   "digest does not match")
    return body


def _unpack(raw: bytes, limits: Limits) -> Any:
    try:
        return msgpack.unpackb(raw, raw=False, strict_map_key=True,
                               max_bin_len=limits.max_request_bytes)
    except Exception as exc:  # msgpack raises several types for a corrupt blob
        raise InvalidArgumentError(f"restore.blob is not a snapshot (corrupt msgpack: "
                                   f"{type(exc).__name__})") from exc


def world_from(data: dict[str, Any], make_engine: Callable[[str], Engine], name: str,
               limits: Limits, engine_name: str | None = None) -> World:
    """A new World rebuilt from snapshot data on a fresh engine (closed again if refused).
    ``engine_name``: the engine the snapshot must be of (the world it replaces)."""
    kind = data.get("engine")
    if not isinstance(kind, str) or (engine_name is not None and kind != engine_name):
        raise InvalidArgumentError(f"the snapshot is of engine {brief(kind)}; this world runs "
                                   f"{engine_name}: restore it into a world of its engine")
    engine = make_engine(kind)
    try:
        state = data.get("engine_state")
        if not isinstance(state, dict):
            raise InvalidArgumentError("the snapshot holds no engine state")
        engine.restore(state)
        world = World(engine, name, limits)
        _restore_registry(world, data)
        checks.check_agrees(world)
    except RemoteError:
        engine.close()
        raise
    except Exception as exc:  # a re-sealed hostile body no check above foresaw (issue 46)
        engine.close()
        raise InvalidArgumentError(
            f"the snapshot is malformed and was not restored: {type(exc).__name__}: "
            f"{brief(str(exc))}") from exc
    return world


def _restore_registry(world: World, data: dict[str, Any]) -> None:
    try:
        infos = [EntityInfo.from_wire(body) for body in data["entities"]]
        poses = unpack_f64(data["initial_poses"], POSE_WIDTH, "initial_poses")
        twists = unpack_f64(data["initial_twists"], TWIST_WIDTH, "initial_twists")
        clock = data["clock"]
        step, base_step = int(clock["step"]), int(clock["base_step"])
        base = (base_step, float(clock["base_time"]), float(clock["base_dt"]))
        modes, ends = dict(data["joint_modes"]), dict(data["wrench_ends"])
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InvalidArgumentError(f"the snapshot's registry is malformed: {brief(exc)}"
                                   ) from exc
    checks.check_infos(infos)
    if len(poses) != len(infos) or len(twists) != len(infos):
        raise InvalidArgumentError("the snapshot's registry and initial states disagree")
    world.entities = {info.name: Entity(info, poses[i].copy(), twists[i].copy())
                      for i, info in enumerate(infos)}
    _restore_meshes(world, data.get("meshes", []))
    world.layout += 1
    world.step_index, world._time_base = step, base
    world.verified_step = step
    world.joints.refresh()
    for joint, mode in modes.items():
        if joint in world.joints.by_name and mode in TARGET_MODES:
            world.joints.by_name[joint] = dataclasses.replace(world.joints.by_name[joint],
                                                              mode=mode)
    world.wrenches.ends = {str(n): (None if e is None else int(e)) for n, e in ends.items()}


def _restore_meshes(world: World, meshes: Any) -> None:
    """The spawned meshes' triangles, checked as spawn checks them, each given to the mesh
    bodies it names (a snapshot older than them has none: those are told as their box)."""
    if not isinstance(meshes, list):
        raise InvalidArgumentError("the snapshot's meshes are malformed")
    for index, body in enumerate(meshes):
        where = f"the snapshot's meshes[{index}]"
        names = body.get("names") if isinstance(body, dict) else None
        if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
            raise InvalidArgumentError(f"{where} names no bodies")
        vertices = mesh_wire.decode_vertices(body.get("vertices"), f"{where}.vertices")
        faces = mesh_wire.decode_faces(body.get("faces"), len(vertices), f"{where}.faces")
        mesh_wire.check_area(vertices, faces, where)
        mesh = frozen_mesh(vertices, faces)
        for name in names:
            entity = world.entities.get(name)
            if entity is None or entity.info.shape != "mesh" or entity.mesh is not None:
                raise InvalidArgumentError(f"{where} names {brief(name)}: no mesh body of "
                                           "the snapshot's, or one given twice")
            entity.mesh = mesh
