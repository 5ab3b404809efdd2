"""The shapes a drawing of a world needs beyond ``list``'s shape and size: a loaded model's
bodies and spawned meshes, as ``get_shapes`` tells them; kept in a recording as arrays so
that a replay draws them as the live view does.

A recording holds them under ``shape_*`` and ``mesh_*`` keys of its ``.npz``: the rows as
``get_shapes`` sends them, and each distinct mesh's vertices and faces once, concatenated.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.client.sdk.values import ShapeInfo, Triangles, grouped_shapes, triangles_of
from galton.protocol import MODEL_SHAPES, EntityInfo, FeatureUnsupportedError, GaltonError

if TYPE_CHECKING:
    from galton.client.sdk.client import Client

log = logging.getLogger("galton.client")

Shapes = dict[str, list[ShapeInfo]]
KEYS = ("shape_names", "shape_counts", "shape_kinds", "shape_sizes", "shape_poses",
        "shape_meshes", "mesh_vertices", "mesh_vertex_counts", "mesh_faces",
        "mesh_face_counts")


def drawn_by_shapes(infos: Sequence[EntityInfo]) -> list[str]:
    """The entities drawn from their ``get_shapes`` rows: loaded models' bodies and spawned
    meshes (a primitive's shape and size say all there is to draw)."""
    return [info.name for info in infos if info.shape in (*MODEL_SHAPES, "mesh")]


def shapes_for_drawing(client: Client, infos: Sequence[EntityInfo]) -> Shapes:
    """These entities' shapes as a drawing needs them; an engine that tells no model's
    shapes still tells its meshes', and entities gone meanwhile are left out."""
    names = drawn_by_shapes(infos)
    try:
        return _asked(client, names)
    except FeatureUnsupportedError as error:
        log.info("links drawn as cubes: %s", error)
        meshes = [info.name for info in infos if info.shape == "mesh"]
        try:
            return _asked(client, meshes) if len(meshes) < len(names) else {}
        except GaltonError:
            return {}
    except GaltonError as error:  # a model deleted meanwhile: drawn by its info alone
        log.info("shapes not told: %s", error)
        return {}


def _asked(client: Client, names: list[str]) -> Shapes:
    return client.get_shapes(names) if names else {}


def pack_shapes(shapes: Mapping[str, Sequence[ShapeInfo]]) -> dict[str, np.ndarray]:
    """Shapes as the arrays a recording keeps (each distinct mesh once)."""
    rows = [shape for entity in shapes.values() for shape in entity]
    table: dict[int, int] = {}
    meshes: list[Triangles] = []
    for shape in rows:
        if shape.vertices is not None and shape.faces is not None \
                and id(shape.vertices) not in table:
            table[id(shape.vertices)] = len(meshes)
            meshes.append((shape.vertices, shape.faces))
    return {
        "shape_names": np.asarray(json.dumps(list(shapes))),
        "shape_counts": np.asarray([len(entity) for entity in shapes.values()], dtype=np.int64),
        "shape_kinds": np.asarray(json.dumps([shape.kind for shape in rows])),
        "shape_sizes": np.asarray([[*s.size, 0.0, 0.0, 0.0][:3] for s in rows]).reshape(-1, 3),
        "shape_poses": np.asarray([s.pose for s in rows], dtype=float).reshape(-1, 7),
        "shape_meshes": np.asarray([table.get(id(s.vertices), -1) for s in rows],
                                   dtype=np.int64),
        "mesh_vertices": np.concatenate([v for v, _ in meshes] or [np.zeros((0, 3))]),
        "mesh_vertex_counts": np.asarray([len(v) for v, _ in meshes], dtype=np.int64),
        "mesh_faces": np.concatenate([f for _, f in meshes] or [np.zeros((0, 3), np.int64)]),
        "mesh_face_counts": np.asarray([len(f) for _, f in meshes], dtype=np.int64),
    }


def unpack_shapes(data: Mapping[str, Any]) -> Shapes:
    """The shapes a recording keeps; none in one made before recordings kept them."""
    if "shape_names" not in data:
        return {}
    got = {key: np.asarray(data[key]) for key in KEYS}
    vertex_ends = np.cumsum(got["mesh_vertex_counts"])
    face_ends = np.cumsum(got["mesh_face_counts"])
    vertex_sets = np.split(got["mesh_vertices"].reshape(-1, 3), vertex_ends[:-1])
    face_sets = np.split(got["mesh_faces"].reshape(-1, 3), face_ends[:-1])
    table = [triangles_of(v, f) for v, f in
             zip(vertex_sets, face_sets, strict=True)] if len(vertex_ends) else []
    return grouped_shapes(json.loads(str(got["shape_names"])),
                          got["shape_counts"].tolist(), json.loads(str(got["shape_kinds"])),
                          got["shape_sizes"].reshape(-1, 3), got["shape_poses"].reshape(-1, 7),
                          got["shape_meshes"].tolist(), table)
