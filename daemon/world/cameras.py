"""Cameras as requests give them: parsed and checked before anything renders, and resolved
to the world frame (a camera attached to a body or link moves with it)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from galton.daemon.engines.base import IMAGE_OUTPUTS, CameraView
from galton.daemon.world.world import World
from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief
from galton.protocol.model import check_name, check_type, finite_number, integer_in
from galton.protocol.vocabulary import check_fields

# A frustum every renderer draws: a nearer plane (MuJoCo fails on 1e-300), or a far plane
# farther than this many near planes, leaves a depth buffer with no usable precision.
MIN_NEAR = 1e-6
MAX_DEPTH_RATIO = 1e9
CAMERA_FIELDS = ("eye", "target", "up", "fov", "width", "height", "near", "far", "outputs",
                 "attach")
MAX_SIDE = 8192  # pixels along one side of an image
DEFAULTS: dict[str, Any] = {"up": (0.0, 0.0, 1.0), "fov": 45.0, "width": 320, "height": 240,
                            "near": 0.01, "far": 100.0, "outputs": ("rgb",)}


@dataclass(frozen=True)
class Camera:
    """A checked camera; with ``attach``, its eye, target and up are in that entity's
    frame (position and orientation), else in the world frame."""

    eye: tuple[float, float, float]
    target: tuple[float, float, float]
    up: tuple[float, float, float]
    fov: float
    width: int
    height: int
    near: float
    far: float
    outputs: tuple[str, ...]
    attach: str | None = None

    @property
    def pixels(self) -> int:
        return self.width * self.height

    def to_wire(self) -> dict[str, Any]:
        return {"eye": list(self.eye), "target": list(self.target), "up": list(self.up),
                "fov": self.fov, "width": self.width, "height": self.height,
                "near": self.near, "far": self.far, "outputs": list(self.outputs),
                "attach": self.attach}


def parse_camera(raw: Any, where: str) -> Camera:
    """A camera map (docs/protocol.md, "render"), every field checked."""
    body = check_type(raw, dict, where)
    check_fields(body, CAMERA_FIELDS, where)
    for key in ("eye", "target"):
        if key not in body:
            raise InvalidArgumentError(f"{where}: missing required field {key!r}")
    values = {**DEFAULTS, **body}
    eye, target = _vector(values["eye"], f"{where}.eye"), _vector(values["target"],
                                                                  f"{where}.target")
    up = _vector(values["up"], f"{where}.up")
    view = np.subtract(target, eye)
    if np.linalg.norm(view) < 1e-9:
        raise InvalidArgumentError(f"{where}: eye and target are the same point")
    scale = float(np.linalg.norm(view)) * float(np.linalg.norm(up))
    if scale == 0.0 or float(np.linalg.norm(np.cross(view, up))) < 1e-9 * scale:
        raise InvalidArgumentError(f"{where}.up is zero or along the view (eye to target)")
    near = finite_number(values["near"], f"{where}.near", low=MIN_NEAR)
    far = finite_number(values["far"], f"{where}.far", low=near, low_open=True,
                        high=near * MAX_DEPTH_RATIO)
    outputs = check_type(values["outputs"], (list, tuple), f"{where}.outputs")
    if not outputs or any(o not in IMAGE_OUTPUTS for o in outputs):
        raise InvalidArgumentError(f"{where}.outputs must be a non-empty list among "
                                   f"{', '.join(IMAGE_OUTPUTS)}, got {brief(outputs)}")
    attach = values.get("attach")
    return Camera(
        eye, target, up, _fov(values["fov"], f"{where}.fov"),
        _side(values["width"], f"{where}.width"), _side(values["height"], f"{where}.height"),
        near, far, tuple(dict.fromkeys(outputs)),
        None if attach is None else check_name(attach, f"{where}.attach"))


def _vector(value: Any, where: str) -> tuple[float, float, float]:
    items = check_type(value, (list, tuple), where)
    if len(items) != 3:
        raise InvalidArgumentError(f"{where} must hold 3 numbers, got {brief(value)}")
    x, y, z = (finite_number(v, f"{where}[{i}]") for i, v in enumerate(items))
    return (x, y, z)


def _fov(value: Any, where: str) -> float:
    """A vertical field of view in degrees, strictly between 0 and 180."""
    fov = finite_number(value, where, low=0.0, high=180.0, low_open=True)
    if fov >= 180.0:
        raise InvalidArgumentError(f"{where} must be below 180 degrees, got {fov:g}")
    return fov


def _side(value: Any, where: str) -> int:
    return integer_in(value, where, 1, MAX_SIDE, " pixels")


def rotate(quaternion: np.ndarray, vector: np.ndarray) -> np.ndarray:
    """``vector`` rotated by the unit quaternion (x, y, z, w)."""
    q, w = quaternion[:3], quaternion[3]
    t = 2.0 * np.cross(q, vector)
    rotated: np.ndarray = vector + w * t + np.cross(q, t)
    return rotated


def view_of(world: World, camera: Camera) -> CameraView:
    """The camera in the world frame (through its entity's pose when attached)."""
    eye, target, up = (np.array(v, dtype=float) for v in (camera.eye, camera.target,
                                                           camera.up))
    if camera.attach is not None:
        poses, _ = world.get_states([camera.attach])
        position, quaternion = poses[0, :3], poses[0, 3:7]
        eye, target = position + rotate(quaternion, eye), position + rotate(quaternion, target)
        up = rotate(quaternion, up)
    return CameraView(eye, target, up / np.linalg.norm(up), camera.fov, camera.width,
                      camera.height, camera.near, camera.far, camera.outputs)
