"""One world drawn in a viser scene: each body as its shape, bodies of one shape, size and
colour batched into one mesh whose instances move with each state sample (one message a
group a frame, not one a body: 500 bodies stay cheap at 20 Hz)."""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import trimesh
import viser

from galton.client.sdk.values import ShapeInfo
from galton.client.view.palette import Rgb, colour_of, opacity_of
from galton.protocol import EntityInfo

Shapes = Mapping[str, Sequence[ShapeInfo]]  # get_shapes' answer for links and meshes

LINK_HALF = 0.02  # a link whose shapes the engine does not tell: a small cube marks it
PLANE_HALF = 5.0  # an unbounded plane is drawn this far from its origin
PLANE_THICKNESS = 0.002


@dataclass(frozen=True)
class GroupKey:
    """What the bodies batched into one mesh share."""

    shape: str
    size: tuple[float, ...]
    colour: Rgb
    opacity: float | None
    # A body drawn as its get_shapes rows (a loaded model's body, a spawned mesh): what
    # they are (shapes_key), so that bodies of one mesh share one batched mesh.
    drawn: tuple[Any, ...] = ()


def shape_mesh(shape: str, size: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The vertices and faces of one body in its own frame (sizes are half sizes,
    docs/protocol.md)."""
    return _as_arrays(_trimesh(shape, size))


def _as_arrays(mesh: Any) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(mesh.vertices, dtype=np.float32), np.asarray(mesh.faces, dtype=np.uint32)


def _trimesh(shape: str, size: Sequence[float]) -> Any:  # a trimesh.Trimesh (untyped)
    creation = trimesh.creation
    if shape == "sphere":
        return creation.icosphere(subdivisions=2, radius=size[0])
    if shape in ("box", "mesh"):  # a mesh whose triangles are not told: its box
        return creation.box(extents=[2 * h for h in size[:3]])
    if shape == "cylinder":
        return creation.cylinder(radius=size[0], height=2 * size[1], sections=24)
    if shape == "capsule":
        return creation.capsule(height=2 * size[1], radius=size[0], count=[12, 12])
    if shape == "plane":
        half = [h if h > 0 else PLANE_HALF for h in [*size, 0.0, 0.0][:2]]
        mesh = creation.box(extents=[2 * half[0], 2 * half[1], PLANE_THICKNESS])
        mesh.apply_translation([0.0, 0.0, -PLANE_THICKNESS / 2])
        return mesh
    return creation.box(extents=[2 * LINK_HALF] * 3)  # a link, a model's root


def shapes_key(shapes: Sequence[ShapeInfo]) -> tuple[Any, ...]:
    """What makes two bodies' shapes draw alike: kinds, sizes, poses and which triangles
    (by their arrays' identity, which the shapes of one reply or recording share)."""
    return tuple((shape.kind, shape.size, np.asarray(shape.pose).tobytes(),
                  0 if shape.vertices is None else id(shape.vertices)) for shape in shapes)


def link_mesh(shapes: Sequence[ShapeInfo]) -> tuple[np.ndarray, np.ndarray]:
    """A body's shapes as one mesh in the body's frame: a mesh as its triangles where they
    are told (else its box), a primitive as its shape."""
    parts = []
    for shape in shapes:
        part = _trimesh(shape.kind, shape.size) if shape.vertices is None or shape.faces is None \
            else trimesh.Trimesh(shape.vertices, shape.faces, process=False)
        pose = np.asarray(shape.pose, dtype=float)
        x, y, z, w = pose[3:] / np.linalg.norm(pose[3:])
        transform = np.eye(4)
        transform[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                             [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                             [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        transform[:3, 3] = pose[:3]
        part.apply_transform(transform)
        parts.append(part)
    return _as_arrays(trimesh.util.concatenate(parts))


def wxyz(poses: np.ndarray) -> np.ndarray:
    """The quaternions of wire poses (x y z qx qy qz qw) in viser's order (w x y z)."""
    return poses[:, [6, 3, 4, 5]]


class WorldDrawing:
    """The batched meshes of one world under ``root``; ``opacity`` below 1 draws a ghost."""

    def __init__(self, scene: viser.SceneApi, root: str, opacity: float | None = None,
                 tint: Rgb | None = None, moving_only: bool = False) -> None:
        self.scene = scene
        self.moving_only = moving_only  # a ghost: static bodies are the live world's
        self.root = root
        self.opacity = opacity
        self.tint = tint
        self.names: tuple[str, ...] = ()
        self.infos: list[EntityInfo] = []  # as listed at the last rebuild
        self._groups: list[tuple[viser.BatchedMeshHandle, np.ndarray]] = []

    def rebuild(self, infos: Sequence[EntityInfo], names: Sequence[str],
                poses: np.ndarray, shapes: Shapes | None = None) -> None:
        """Draw these entities afresh (the scene changed): one batched mesh per group; a
        body with ``shapes`` (a loaded model's, a spawned mesh) is drawn as them (a model's
        body whose shapes are not told as a small cube, a mesh's as its box)."""
        self.clear()
        self.infos = list(infos)
        by_name = {info.name: info for info in infos}
        shapes = shapes or {}
        members: dict[GroupKey, list[int]] = defaultdict(list)
        drawing: dict[tuple[Any, ...], Sequence[ShapeInfo]] = {}
        for index, name in enumerate(names):
            info = by_name.get(name, EntityInfo(name, "link"))
            if self.moving_only and info.static:
                continue
            colour = self.tint or colour_of(info.tags, info.static)
            opacity = min(self.opacity or 1.0, opacity_of(info.tags) or 1.0)
            told = shapes.get(name)
            drawn = shapes_key(told) if told else ()
            if told:
                drawing[drawn] = told
            members[GroupKey(info.shape, tuple(info.size), colour,
                             None if opacity >= 1.0 else opacity, drawn)].append(index)
        for number, (key, indices) in enumerate(members.items()):
            rows = np.asarray(indices)
            vertices, faces = link_mesh(drawing[key.drawn]) if key.drawn \
                else shape_mesh(key.shape, key.size)
            handle = self.scene.add_batched_meshes_simple(
                f"{self.root}/group{number}", vertices, faces,
                batched_wxyzs=wxyz(poses[rows]), batched_positions=poses[rows, :3],
                batched_colors=key.colour, opacity=key.opacity, lod="off",
                cast_shadow=False, receive_shadow=False)
            self._groups.append((handle, rows))
        self.names = tuple(names)

    def update(self, poses: np.ndarray) -> None:
        """Move every instance to its pose (rows in the order of ``names``)."""
        for handle, rows in self._groups:
            handle.batched_positions = poses[rows, :3]
            handle.batched_wxyzs = wxyz(poses[rows])

    def vertices_of(self, name: str) -> np.ndarray:
        """The vertices (in its own frame) of the mesh that draws entity ``name``."""
        index = self.names.index(name)
        for handle, rows in self._groups:
            if index in rows:
                return np.asarray(handle.vertices)
        raise KeyError(name)

    def clear(self) -> None:
        for handle, _ in self._groups:
            handle.remove()
        self._groups = []
        self.names = ()


def framing(infos: Sequence[EntityInfo], names: Sequence[str],
            poses: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """A camera position and look-at point that frame the bodies (planes aside), seen from
    the front (-y), z up: a falling body moves down the screen. None: no body to frame."""
    shapes = {info.name: info.shape for info in infos}
    rows = [i for i, name in enumerate(names) if shapes.get(name) != "plane"]
    if not rows:
        return None
    points = poses[rows, :3]
    low, high = points.min(axis=0), points.max(axis=0)
    low[2] = min(low[2], 0.0)
    centre = (low + high) / 2
    reach = max(float(np.max(high - low)), 0.5)
    return centre + np.array([0.0, -1.4 * reach - 0.3, 0.25 * reach]), centre
