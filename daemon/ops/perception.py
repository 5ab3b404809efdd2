"""Perception operations: render, add_camera, remove_camera, cameras, raycast, contacts
(docs/protocol.md). Every argument is checked, and every limit, before the engine works."""

from __future__ import annotations

import statistics
import time
from typing import Any

import numpy as np

from galton.daemon.core.reply_limit import RAW_PIXEL_BYTES, RAY_BYTES, require_room
from galton.daemon.ops.binding import scene_op
from galton.daemon.world.cameras import Camera, parse_camera, view_of
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError, NotFoundError, ResourceLimitError, pack_f64
from galton.protocol import requests as rq
from galton.protocol.errors import brief
from galton.protocol.model import check_names, check_type, decode_directions, decode_points
from galton.protocol.png import depth_png, encode_png, segmentation_png
from galton.protocol.vocabulary import MAX_CAMERA_NAME, check_fields

MAX_NAMED_CAMERAS = 32


def _cameras_of(world: World) -> dict[str, Camera]:
    named: dict[str, Camera] = world.cameras
    return named


def _request_camera(world: World, raw: Any, where: str) -> Camera:
    """A render request's camera: a full camera map, or {"camera": NAME[, "outputs"]}."""
    body = check_type(raw, dict, where)
    if "camera" not in body:
        return parse_camera(body, where)
    check_fields(body, ("camera", "outputs"), where)
    name = check_type(body["camera"], str, f"{where}.camera")
    named = _cameras_of(world).get(name)
    if named is None:
        raise NotFoundError(f"no camera named {brief(name)}; add_camera makes one")
    if "outputs" not in body:
        return named
    spec = parse_camera({**named.to_wire(), "outputs": body["outputs"]}, where)
    return spec


@scene_op("render")
def render(world: World, request: rq.Render) -> dict[str, Any]:
    raw = request.cameras
    fmt = request.format
    cameras = [_request_camera(world, c, f"render.cameras[{i}]") for i, c in enumerate(raw)]
    pixels = sum(c.pixels for c in cameras)
    if pixels > world.limits.max_pixels:
        raise ResourceLimitError(f"render asks for {pixels} pixels; at most "
                                 f"{world.limits.max_pixels} a request",
                                 {"limit": "max_pixels", "max": world.limits.max_pixels})
    if fmt == "raw":
        size = sum(c.pixels * RAW_PIXEL_BYTES[kind] for c in cameras for kind in c.outputs)
        require_room("this render's reply", size, world.limits.max_reply_bytes,
                     "ask for fewer pixels or outputs, or format png")
    for camera in cameras:
        if camera.attach is not None:
            world.require_known([camera.attach])
    _require_time(world, pixels, fmt)
    world.verify()
    started = time.perf_counter()
    images, labels = world.engine.render([view_of(world, c) for c in cameras])
    encoded = [_image(c, i, fmt) for c, i in zip(cameras, images, strict=True)]
    _measured(world, pixels, time.perf_counter() - started, fmt)
    return {"images": encoded, "labels": labels, "format": fmt}


# Renders this small are never refused for time (65,536 pixels at even 1 µs each: 65 ms),
# and renders from LEARNT_FROM_PIXELS teach the cost per pixel (a smaller one is mostly its
# fixed cost; a larger estimate from it only refuses more until bigger ones correct it).
MEASURED_FROM_PIXELS = 65_536
LEARNT_FROM_PIXELS = 4_096
PNG_FACTOR = 2.0  # a png render costs about this many raw ones (zlib on the physics thread)


def _require_time(world: World, pixels: int, fmt: str) -> None:
    """Refuse up front a render expected to hold the physics thread past
    ``max_render_seconds`` (issue 46: one 4096² render stalled a playing world for 2.6-9.4
    s), saying how many pixels fit."""
    budget = world.limits.max_render_seconds
    cost = statistics.median(world.render_costs) * (PNG_FACTOR if fmt == "png" else 1.0)
    expected = pixels * cost
    if expected <= budget or pixels < MEASURED_FROM_PIXELS or \
            "render" not in world.engine.capabilities().features:  # the engine says why not
        return
    fits = int(budget / cost)
    raise ResourceLimitError(
        f"render asks for {pixels} pixels: about {expected:.2f} s of the physics thread at "
        f"this engine's measured {1e-6 / cost:.1f} Mpixel/s ({fmt}), past "
        f"max_render_seconds {budget:g} s; ask for at most {fits} pixels",
        {"limit": "max_render_seconds", "max": budget, "pixels": fits})


def _measured(world: World, pixels: int, seconds: float, fmt: str) -> None:
    """Learn the engine's cost per raw pixel from a render big enough to show it (one of
    the samples whose median is the estimate: a one-off slow render does not move it)."""
    if pixels >= LEARNT_FROM_PIXELS:
        world.render_costs.append(seconds / pixels / (PNG_FACTOR if fmt == "png" else 1.0))


def _image(camera: Camera, image: dict[str, np.ndarray], fmt: str) -> dict[str, Any]:
    out: dict[str, Any] = {"width": camera.width, "height": camera.height}
    for kind in camera.outputs:
        pixels = image[kind]
        if fmt == "raw":
            out[kind] = np.ascontiguousarray(pixels, dtype=_raw_dtype(kind)).tobytes()
        elif kind == "rgb":
            out[kind] = encode_png(np.ascontiguousarray(pixels, dtype=np.uint8))
        elif kind == "depth":
            out[kind] = depth_png(pixels)
        else:
            out[kind] = segmentation_png(pixels)
    return out


def _raw_dtype(kind: str) -> str:
    return {"rgb": "u1", "depth": "<f4", "segmentation": "<i4"}[kind]


@scene_op("add_camera")
def add_camera(world: World, request: rq.AddCamera) -> dict[str, Any]:
    name = request.name
    if not name.isprintable():  # its length is declared (protocol/requests.py)
        raise InvalidArgumentError(f"add_camera.name {brief(name)} must be "
                                   f"1-{MAX_CAMERA_NAME} printable characters")
    camera = parse_camera(request.camera, "add_camera.camera")
    if camera.attach is not None:
        world.require_known([camera.attach])
    cameras = _cameras_of(world)
    if name not in cameras and len(cameras) >= MAX_NAMED_CAMERAS:
        raise ResourceLimitError(f"the world holds {len(cameras)} named cameras, at most "
                                 f"{MAX_NAMED_CAMERAS}", {"limit": "cameras",
                                                          "max": MAX_NAMED_CAMERAS})
    cameras[name] = camera
    return {"name": name, "camera": camera.to_wire()}


@scene_op("remove_camera")
def remove_camera(world: World, request: rq.Named) -> dict[str, Any]:
    name = request.name
    if _cameras_of(world).pop(name, None) is None:
        raise NotFoundError(f"no camera named {brief(name)}")
    return {"count": 1}


@scene_op("cameras")
def cameras(world: World, request: rq.NoArgs) -> dict[str, Any]:
    return {"cameras": [{"name": n, **c.to_wire()} for n, c in _cameras_of(world).items()]}


@scene_op("raycast")
def raycast(world: World, request: rq.Raycast) -> dict[str, Any]:
    raw = request.origins
    count = _row_count(raw)
    if count > world.limits.max_rays:
        raise ResourceLimitError(f"raycast casts {count} rays; at most {world.limits.max_rays}",
                                 {"limit": "max_rays", "max": world.limits.max_rays})
    require_room("this raycast's reply", count * RAY_BYTES, world.limits.max_reply_bytes,
                 "cast fewer rays a request")
    origins = decode_points(raw, count, "raycast.origins")
    if (request.directions is None) == (request.ends is None):
        raise InvalidArgumentError("raycast needs exactly one of 'directions' or 'ends'")
    max_length = request.max_length
    if request.ends is not None:
        with np.errstate(over="ignore", invalid="ignore"):
            vectors = decode_points(request.ends, count, "raycast.ends") - origins
        if not np.isfinite(vectors).all():
            raise InvalidArgumentError(
                f"raycast ray {int(np.argmin(np.isfinite(vectors).all(axis=1)))}: its end is "
                "too far from its origin (the difference overflows)")
    else:
        vectors = decode_directions(request.directions, count, "raycast.directions")
    units, norms = unit_rows(vectors)
    lengths = norms if request.ends is not None else np.full(count, max_length)
    if not np.isfinite(lengths).all():
        raise InvalidArgumentError(f"raycast ray {int(np.argmin(np.isfinite(lengths)))}: its "
                                   "end is too far from its origin (the length overflows)")
    world.verify()
    hits, entities, points, normals, distances = world.engine.raycast(
        origins, units, float(lengths.max()) if count else max_length)
    beyond = hits & (distances > lengths)  # a ray given an end stops there
    if beyond.any():
        hits = hits & ~beyond
        points[beyond], normals[beyond], distances[beyond] = np.nan, np.nan, np.nan
        entities = [("" if beyond[i] else e) for i, e in enumerate(entities)]
    return {"hits": np.asarray(hits, dtype=np.uint8).tobytes(), "entities": entities,
            "points": pack_f64(points), "normals": pack_f64(normals),
            "distances": pack_f64(distances)}


def unit_rows(vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each row scaled to length 1 and its length (inf where it overflows), refusing a zero
    one; scaled by its largest component
    first, so that a huge direction (1e200) does not overflow its norm to inf and become
    zero (MuJoCo's mj_ray aborts the process on a zero direction)."""
    largest = np.abs(vectors).max(axis=1, initial=0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = vectors / largest[:, None]
    with np.errstate(over="ignore"):
        norms = largest * np.linalg.norm(scaled, axis=1)
    tiny = ~(norms >= 1e-12)
    if tiny.any():
        raise InvalidArgumentError(f"raycast ray {int(np.argmax(tiny))} has a zero "
                                   "direction (or its end is its origin)")
    return scaled / np.linalg.norm(scaled, axis=1)[:, None], norms


def _row_count(raw: Any) -> int:
    if not isinstance(raw, bytes | bytearray):
        raise InvalidArgumentError(f"raycast.origins must be msgpack bin of float64 rows of "
                                   f"3, got {brief(raw)}")
    if len(raw) % 24:
        raise InvalidArgumentError(f"raycast.origins holds {len(raw)} bytes, not whole rows "
                                   "of 3 float64")
    return len(raw) // 24


@scene_op("contacts")
def contacts(world: World, request: rq.NamesOrAll) -> dict[str, Any]:
    raw = request.names
    names = None if raw is None else check_names(raw, "contacts.names")
    if names is not None:
        world.require_known(names)
    world.verify()
    a, b, positions, normals, forces, penetrations = world.engine.contacts(names)
    return {"count": len(a), "a": a, "b": b, "positions": pack_f64(positions),
            "normals": pack_f64(normals), "forces": pack_f64(forces),
            "penetrations": pack_f64(penetrations)}
