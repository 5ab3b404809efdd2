"""One SpawnEntity request onto ``spawn`` (our primitives, ``galton://SHAPE?...``) or
``load_model`` (URDF and MJCF, by file or as a string), with the standard's result codes.

A model is loaded with its entity and joint names prefixed ``<name>/`` when a name is
given; its ``entity_name`` is the model's root entity, which DeleteEntity removes whole."""

from __future__ import annotations

import math
from collections.abc import Generator
from typing import Any
from urllib.parse import parse_qs, urlsplit

from galton.daemon.fronts.ros2 import codes
from galton.daemon.fronts.ros2.messages import packed, pose_row
from galton.daemon.fronts.ros2.native import NativeRequest, Refusal, ask
from galton.protocol import Reply, ResultCode

Spawned = Generator[NativeRequest, Reply, tuple[int, str, str]]
RENAME_TRIES = 20
PRIMITIVE_SCHEME = "galton"
MODEL_SUFFIXES = {".urdf": "urdf", ".xml": "mjcf", ".mjcf": "mjcf"}


def spawn_one(request: Any) -> Spawned:
    """(msg/Result code, message, entity name) of one SpawnEntity(-like) request."""
    try:
        frame = request.initial_pose.header.frame_id
        if frame not in ("", "world"):
            raise Refusal(codes.SPAWN_INVALID_POSE, f"frame {frame!r} is unknown: spawn in "
                          "the world frame ('' or 'world')")
        resource = request.entity_resource
        if not resource.uri and not resource.resource_string:
            raise Refusal(codes.NO_RESOURCE, "both uri and resource_string are empty")
        pose = _checked_pose(pose_row(request.initial_pose.pose))
        if resource.uri.startswith(f"{PRIMITIVE_SCHEME}://"):
            name = yield from _spawn_primitive(request, resource.uri, pose)
        else:
            name = yield from _load_model(request, resource, pose)
        return codes.OK, "", name
    except Refusal as refusal:
        return refusal.code, refusal.message, ""


def _checked_pose(pose: list[float]) -> list[float]:
    """Refused before anything is spawned: a non-finite pose or a zero quaternion."""
    if not all(math.isfinite(v) for v in pose) or not any(pose[3:]):
        raise Refusal(codes.SPAWN_INVALID_POSE, f"initial_pose {pose} is not a pose: "
                      "finite values and a non-zero quaternion (x, y, z, w)")
    return pose


def _names(request: Any, fallback: str) -> list[str]:
    """Names to try, in order: the requested one, then renamed ones if allowed."""
    base = request.name or fallback
    if not request.name and not request.allow_renaming:
        raise Refusal(codes.NAME_INVALID, "the name is empty and allow_renaming is false")
    tries = [base] if request.name else []
    if request.allow_renaming:
        tries += [f"{base}_{n}" for n in range(1, RENAME_TRIES + 1)]
    return tries


def _spawn_code(reply: Reply) -> int | None:
    if reply.code == ResultCode.NAME_NOT_UNIQUE:
        return codes.NAME_NOT_UNIQUE
    if reply.code == ResultCode.INVALID_ARGUMENT:
        if "quaternion" in reply.message:
            return codes.SPAWN_INVALID_POSE
        if "missing_file" in reply.details:
            return codes.MISSING_ASSETS
        return codes.RESOURCE_PARSE_ERROR
    if reply.code == ResultCode.FEATURE_UNSUPPORTED:
        return codes.UNSUPPORTED_FORMAT
    return None


def _first_free(request: Any, fallback: str, attempt: Any) -> Generator[
        NativeRequest, Reply, str]:
    """Run ``attempt(name)`` for each name to try until one is not taken."""
    tries = _names(request, fallback)
    for index, name in enumerate(tries):
        try:
            return str((yield from attempt(name)))
        except Refusal as refusal:
            if refusal.code != codes.NAME_NOT_UNIQUE or index == len(tries) - 1:
                raise
    raise Refusal(codes.NAME_NOT_UNIQUE, "no free name")  # tries is never empty


def _primitive_group(uri: str) -> dict[str, Any]:
    """A spawn group from ``galton://SHAPE?size=A,B&mass=M&static=true&tags=a,b``."""
    parts = urlsplit(uri)
    query = {key: values[-1] for key, values in parse_qs(parts.query).items()}
    group: dict[str, Any] = {"shape": parts.netloc}
    try:
        group["size"] = [float(v) for v in query.pop("size", "").split(",") if v]
        for key in ("mass", "friction", "restitution"):
            if key in query:
                group[key] = float(query.pop(key))
    except ValueError as exc:
        raise Refusal(codes.RESOURCE_PARSE_ERROR, f"{uri}: {exc}") from exc
    group["static"] = query.pop("static", "false").lower() in ("1", "true", "yes")
    if "tags" in query:
        group["tags"] = [tag for tag in query.pop("tags").split(",") if tag]
    if query:
        raise Refusal(codes.RESOURCE_PARSE_ERROR, f"{uri}: unknown parameters "
                      f"{sorted(query)}; it takes size, mass, friction, restitution, "
                      "static, tags")
    return group


def _spawn_primitive(request: Any, uri: str, pose: list[float]) -> Generator[
        NativeRequest, Reply, str]:
    group = _primitive_group(uri)

    def attempt(name: str) -> Generator[NativeRequest, Reply, str]:
        spawned = yield from ask("spawn", {"groups": [
            {**group, "names": [name], "poses": packed([pose])}]}, code_of=_spawn_code)
        return str(spawned["names"][0])
    return (yield from _first_free(request, group["shape"], attempt))


def _model_source(resource: Any) -> dict[str, Any]:
    """load_model's format and text or path for a Resource."""
    if resource.uri:
        uri = resource.uri
        path = urlsplit(uri).path if uri.startswith("file://") else uri
        if not path.startswith("/"):
            raise Refusal(codes.UNSUPPORTED_FORMAT, f"uri {uri!r}: give an absolute path "
                          "or file:// URI on the daemon's machine, a galton:// primitive, "
                          "or the model in resource_string")
        suffix = path[path.rfind("."):].lower() if "." in path else ""
        if suffix not in MODEL_SUFFIXES:
            raise Refusal(codes.UNSUPPORTED_FORMAT, f"uri {uri!r}: models are .urdf, "
                          ".xml or .mjcf files")
        return {"format": MODEL_SUFFIXES[suffix], "path": path}
    text = resource.resource_string
    head = text[:4096]
    fmt = "mjcf" if "<mujoco" in head else "urdf" if "<robot" in head else None
    if fmt is None:
        raise Refusal(codes.UNSUPPORTED_FORMAT, "resource_string is neither URDF (<robot>) "
                      "nor MJCF (<mujoco>)")
    return {"format": fmt, "text": text}


def _load_model(request: Any, resource: Any, pose: list[float]) -> Generator[
        NativeRequest, Reply, str]:
    source = _model_source(resource)
    if not request.name and not request.allow_renaming:
        loaded = yield from ask("load_model", source, code_of=_spawn_code)
        root = str(loaded["names"][0])
    else:
        def attempt(name: str) -> Generator[NativeRequest, Reply, str]:
            loaded = yield from ask("load_model", {**source, "prefix": f"{name}/"},
                                    code_of=_spawn_code)
            return str(loaded["names"][0])
        root = yield from _first_free(request, "model", attempt)
    if pose != [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]:
        yield from ask("set_states", {"names": [root], "poses": packed([pose])},
                       code_of=_spawn_code)
    return root
