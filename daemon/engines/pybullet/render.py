"""Pictures from a PyBullet world: TinyRenderer, PyBullet's software rasteriser (no window,
no GPU, no GL context to leak), and the entity names behind its pixels.

PyBullet names what a pixel or a ray shows by a code, ``body id + (link index + 1) << 24``
(ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX; the base is link -1). ``entity_codes`` maps
each code to an entity name: a spawned body or a model's root by its base, a link by its
own index, and a hidden link (an MJCF importer's joint link) as its nearest shown ancestor.

TinyRenderer's depth buffer holds OpenGL's non-linear depth d in [0, 1]; the distance along
the view axis is far * near / (far - (far - near) * d), and d = 1 (the cleared buffer) is
nothing within far. Its rows run top first, as the contract wants.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.base import CameraView
from galton.daemon.engines.pybullet.joints import Tree
from galton.daemon.engines.pybullet.rebuild import Body
from galton.daemon.engines.pybullet.robots import Robots

LINK_SHIFT = 24  # a segmentation code's link index (plus one) sits above this bit
BODY_BITS = (1 << LINK_SHIFT) - 1
RENDER_BACKEND = "tinyrenderer"
Images = dict[str, np.ndarray]


def code(uid: int, link: int) -> int:
    """PyBullet's code for a body's link (-1: its base)."""
    return uid + ((link + 1) << LINK_SHIFT)


def entity_codes(bc: BulletClient, bodies: Mapping[str, Body], robots: Robots
                 ) -> dict[int, str]:
    """Every entity's code, with the codes of hidden links as their shown ancestors'."""
    codes = {code(body.uid, -1): name for name, body in bodies.items()}
    for root, model in robots.models.items():
        uid = bodies[root].uid
        tree = Tree(bc, uid, root, model.links) if None in model.links else None
        for j, link in enumerate(model.links):
            shown = link if link is not None or tree is None else tree.parent(j)
            if shown is not None:
                codes[code(uid, j)] = shown
    return codes


def render(bc: BulletClient, codes: Mapping[int, str], cameras: Sequence[CameraView]
           ) -> tuple[list[Images], list[str]]:
    """One dict of images per camera; the segmentation indexes the names returned, which
    are the entities seen by any camera, sorted."""
    shots = [_shoot(bc, camera) for camera in cameras]
    masks = [mask for _, mask in shots if mask is not None]
    labels, table = _labels(codes, masks)
    images = []
    for camera, (found, mask) in zip(cameras, shots, strict=True):
        if mask is not None:
            found["segmentation"] = _segmentation(mask, table)
        images.append({name: found[name] for name in camera.outputs})
    return images, labels


def _shoot(bc: BulletClient, camera: CameraView) -> tuple[Images, np.ndarray | None]:
    """One getCameraImage: rgb and depth as the contract has them, the raw mask if asked."""
    wants_mask = "segmentation" in camera.outputs
    view = bc.computeViewMatrix([float(v) for v in camera.eye],
                                [float(v) for v in camera.target],
                                [float(v) for v in camera.up])
    projection = bc.computeProjectionMatrixFOV(
        float(camera.fov_deg), camera.width / camera.height, float(camera.near),
        float(camera.far))
    flags = (pybullet.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX if wants_mask
             else pybullet.ER_NO_SEGMENTATION_MASK)
    _, _, rgba, depth, mask = bc.getCameraImage(
        camera.width, camera.height, view, projection, renderer=pybullet.ER_TINY_RENDERER,
        flags=flags)
    found: Images = {}
    if "rgb" in camera.outputs:
        found["rgb"] = np.ascontiguousarray(
            np.asarray(rgba, np.uint8).reshape(camera.height, camera.width, 4)[:, :, :3])
    if "depth" in camera.outputs:
        found["depth"] = metric_depth(np.asarray(depth, np.float32).reshape(
            camera.height, camera.width), camera.near, camera.far)
    shaped = np.asarray(mask, np.int32).reshape(camera.height, camera.width)
    return found, shaped if wants_mask else None


def metric_depth(buffer: np.ndarray, near: float, far: float) -> np.ndarray:
    """OpenGL depth in [0, 1] as metres along the view axis (float32), inf for d = 1."""
    d = buffer.astype(np.float64)
    with np.errstate(divide="ignore"):
        metres = far * near / (far - (far - near) * d)
    return np.where(d >= 1.0, np.inf, metres).astype(np.float32)


def _split(masks: Sequence[np.ndarray]) -> tuple[int, int]:
    """The largest body id and link code (index + 1) in these masks."""
    ids = [int((m & BODY_BITS).max(initial=0)) for m in masks]
    links = [int((m[m >= 0] >> LINK_SHIFT).max(initial=0)) for m in masks]
    return max(ids, default=0), max(links, default=0)


def _labels(codes: Mapping[int, str], masks: Sequence[np.ndarray]
            ) -> tuple[list[str], np.ndarray]:
    """The entity names seen, and a table from (link + 1, body id) to their index (-1:
    not an entity), flattened with rows of ``max id + 1``."""
    top_id, top_link = _split(masks)
    width = top_id + 1
    seen = np.zeros((top_link + 1) * width, bool)
    for mask in masks:
        seen[_flat(mask, width)[mask >= 0]] = True
    named = {int(k): codes.get(_code(int(k), width)) for k in np.flatnonzero(seen)}
    labels = sorted({name for name in named.values() if name is not None})
    index = {name: k for k, name in enumerate(labels)}
    table = np.full(seen.shape, -1, np.int32)
    for flat_code, name in named.items():
        if name is not None:
            table[flat_code] = index[name]
    return labels, table.reshape(top_link + 1, width)


def _flat(mask: np.ndarray, width: int) -> np.ndarray:
    safe = np.maximum(mask, 0)
    flat: np.ndarray = (safe >> LINK_SHIFT) * width + (safe & BODY_BITS)
    return flat


def _code(flat: int, width: int) -> int:
    link_plus_one, uid = divmod(flat, width)
    return code(uid, link_plus_one - 1)


def _segmentation(mask: np.ndarray, table: np.ndarray) -> np.ndarray:
    out: np.ndarray = table.reshape(-1)[_flat(mask, table.shape[1])]
    return np.where(mask >= 0, out, -1).astype(np.int32)
