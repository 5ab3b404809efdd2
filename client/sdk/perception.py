"""The SDK's perception (issue 26), mixed into Client: headless cameras, ray casts and
contacts, answered as numpy arrays.

>>> top = camera(eye=(0, 0, 2), target=(0, 0, 0), up=(0, 1, 0), size=(64, 48),
...              outputs=("rgb", "depth", "segmentation"))
>>> image = sim.render(top)[0]                  # image.rgb (48, 64, 3) uint8, image.depth
>>> sim.add_camera("wrist", camera((0.1, 0, 0), (1, 0, 0), attach="arm/hand"))
>>> sim.render({"camera": "wrist"})             # follows the link as it moves
>>> hits = sim.raycast([[0, 0, 1]], directions=[[0, 0, -1]])
>>> sim.contacts(["box"]).forces.sum()
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from galton.client.sdk.joints import float_array, given
from galton.client.sdk.values import Contacts, Image, RayHits
from galton.protocol import InvalidArgumentError, Reply, pack_f64
from galton.protocol import requests as rq
from galton.protocol.replies import CamerasReply, RenderReply, decode_result
from galton.protocol.vocabulary import ImageFormat

if TYPE_CHECKING:
    CameraMap = Mapping[str, Any]



def camera(eye: ArrayLike, target: ArrayLike, *, up: ArrayLike | None = None,
           fov: float | None = None, size: tuple[int, int] | None = None,
           near: float | None = None, far: float | None = None,
           outputs: Sequence[str] | None = None, attach: str | None = None) -> dict[str, Any]:
    """A camera map (docs/protocol.md, "render") looking from ``eye`` at ``target``;
    ``size`` is (width, height) in pixels; a field left None takes the daemon's default.
    With ``attach``, eye, target and up are in that body's or link's frame."""
    found: dict[str, Any] = {"eye": _vector(eye, "eye"), "target": _vector(target, "target")}
    if up is not None:
        found["up"] = _vector(up, "up")
    if size is not None:
        found["width"], found["height"] = int(size[0]), int(size[1])
    found.update({key: float(value) for key, value in given(fov=fov, near=near, far=far).items()})
    if outputs is not None:
        found["outputs"] = [outputs] if isinstance(outputs, str) else list(outputs)
    if attach is not None:
        found["attach"] = attach
    return found


def _vector(value: ArrayLike, name: str) -> list[float]:
    array = float_array(value, f"a camera's {name}").reshape(-1)
    if array.shape != (3,):
        raise InvalidArgumentError(f"a camera's {name} holds 3 numbers, got {value!r}")
    return [float(v) for v in array]


def _rows(value: ArrayLike, name: str) -> np.ndarray:
    """Points or vectors as (n, 3) float64 (one row may be given alone)."""
    array = float_array(value, f"raycast {name}")
    if array.ndim == 1:
        array = array.reshape(1, -1)
    if array.ndim != 2 or array.shape[1] != 3:
        raise InvalidArgumentError(f"raycast {name} must be rows of 3 numbers (n, 3), got "
                                   f"shape {array.shape}")
    return array


class PerceptionMethods:
    """Client methods for cameras, images, ray casts and contacts."""

    if TYPE_CHECKING:
        def _send(self, op: str, request: rq.Args, timeout: float | None = None
                  ) -> Reply: ...

    def render(self, cameras: CameraMap | Sequence[CameraMap], format: str = "raw",
               timeout: float | None = None) -> list[Image]:
        """One image per camera (a camera map, ``{"camera": NAME}`` for a named one, or a
        list of them), decoded to numpy arrays; ``format="png"`` sends them compressed
        (depth then in whole millimetres)."""
        chosen = [cameras] if isinstance(cameras, Mapping) else list(cameras)
        request = rq.Render(cameras=[dict(c) for c in chosen],
                            format=cast(ImageFormat, format))
        reply = self._send("render", request, timeout)
        rendered = decode_result(RenderReply, reply.result)
        labels = [str(n) for n in rendered.labels]
        return [Image.from_wire(image, labels, rendered.format, reply)
                for image in rendered.images]

    def add_camera(self, name: str, camera: CameraMap) -> dict[str, Any]:
        """Keep a named camera in the world (replacing one of that name); render it with
        ``{"camera": name}``. Returns the camera map as the daemon checked it."""
        request = rq.AddCamera(name=name, camera=dict(camera))
        camera_map: dict[str, Any] = self._send("add_camera", request).result
        return dict(camera_map["camera"])

    def remove_camera(self, name: str) -> None:
        self._send("remove_camera", rq.Named(name=name))

    def cameras(self) -> dict[str, dict[str, Any]]:
        """The world's named cameras: name -> camera map."""
        rows = decode_result(CamerasReply, self._send("cameras", rq.NoArgs()).result).cameras
        return {str(row["name"]): {k: v for k, v in row.items() if k != "name"}
                for row in rows}

    def raycast(self, origins: ArrayLike, directions: ArrayLike | None = None,
                ends: ArrayLike | None = None, max_length: float | None = None,
                timeout: float | None = None) -> RayHits:
        """Cast rays from ``origins`` (n, 3) along ``directions`` (any length, normalised;
        they reach ``max_length``) or to ``ends``: exactly one of the two."""
        if (directions is None) == (ends is None):
            raise InvalidArgumentError("raycast takes exactly one of directions or ends")
        request = rq.Raycast(
            origins=pack_f64(_rows(origins, "origins")),
            directions=None if directions is None else pack_f64(_rows(directions,
                                                                       "directions")),
            ends=None if ends is None else pack_f64(_rows(ends, "ends")),
            **given(max_length=None if max_length is None else float(max_length)))
        return RayHits.from_reply(self._send("raycast", request, timeout))

    def contacts(self, names: Sequence[str] | None = None) -> Contacts:
        """The contact points of the last step (only those involving ``names`` if given)."""
        listed = None if names is None else [names] if isinstance(names, str) else list(names)
        return Contacts.from_reply(self._send("contacts", rq.NamesOrAll(names=listed)))
