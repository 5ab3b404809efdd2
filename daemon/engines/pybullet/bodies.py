"""What the PyBullet engine hands to PyBullet: collision and visual shapes shared through
caches (the visual meshes in meshes.py), the mass properties PyBullet would
otherwise approximate, bodies made with their true ids, and model files.

Sizes are the protocol's half sizes: sphere (radius,), box (hx, hy, hz), cylinder and
capsule (radius, half_length) with the axis along local z, plane (hx, hy) for looks only
(a PyBullet plane is infinite). A capsule's half_length is half its cylindrical part, as in
MuJoCo, and PyBullet's capsule ``height`` is that part's full length.
"""

from __future__ import annotations

import itertools
import os
import tempfile
import xml.etree.ElementTree as ElementTree
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet import mjcf
from galton.daemon.engines.pybullet.files import fix_mjcf_inertia
from galton.daemon.engines.pybullet.meshes import shared_mesh
from galton.protocol import InvalidArgumentError, OperationFailedError

# Shapes whose collision margin is a free setting. A sphere's and a capsule's margin is
# their radius (Bullet models them as a point or a segment grown by the margin), so
# changeDynamics(collisionMargin=...) leaves them as they are.
MARGIN_SHAPES = ("box", "cylinder", "plane")
# A box or cylinder keeps its outer size when its margin changes (Bullet shrinks the inner
# shape by the margin), so the margin must stay well below the smallest half size.
MARGIN_CAP = 0.5

MODEL_ROOTS = {"urdf": "robot", "mjcf": "mujoco"}  # root element of each model format
# Inertia from the file, and true cylinders rather than their convex hulls.
URDF_FLAGS = pybullet.URDF_USE_INERTIA_FROM_FILE | pybullet.URDF_USE_IMPLICIT_CYLINDER
WHITE = (1.0, 1.0, 1.0, 1.0)
LONG_LINE = 4096  # characters: a model's longer lines are broken between elements


def as_rgba(colour: Sequence[float]) -> tuple[float, float, float, float]:
    """A colour as four plain floats, whatever numbers it was given as."""
    red, green, blue, alpha = (float(c) for c in colour)
    return (red, green, blue, alpha)


def collision_args(shape: str, size: tuple[float, ...]) -> dict[str, Any]:
    """Keyword arguments of createCollisionShape for one protocol shape and size."""
    if shape == "sphere":
        return {"shapeType": pybullet.GEOM_SPHERE, "radius": size[0]}
    if shape == "box":
        return {"shapeType": pybullet.GEOM_BOX, "halfExtents": list(size)}
    if shape == "cylinder":
        return {"shapeType": pybullet.GEOM_CYLINDER, "radius": size[0], "height": 2 * size[1]}
    if shape == "capsule":
        return {"shapeType": pybullet.GEOM_CAPSULE, "radius": size[0], "height": 2 * size[1]}
    if shape == "plane":
        return {"shapeType": pybullet.GEOM_PLANE, "planeNormal": [0, 0, 1]}
    raise ValueError(f"unknown shape {shape!r}")






def margin_for(shape: str, size: tuple[float, ...], margin: float) -> float | None:
    """The collision margin to give this shape, or None where Bullet fixes it (radius)."""
    if shape not in MARGIN_SHAPES:
        return None
    if shape == "plane":
        return margin
    smallest = min(size) if shape == "box" else min(size[0], size[1])
    return min(margin, MARGIN_CAP * smallest)


Link = tuple[float, tuple[float, ...]]  # a model link's mass and inertia diagonal


class ShapeCache:
    """One collision shape per (shape, size), and one visual shape per (shape, size, colour),
    reused by every body that has it.

    PyBullet's removeBody never frees a shape (only resetSimulation does), so a shape made
    per body would leak with every spawn and delete. Visual shapes are given explicitly, as
    small meshes: without one, PyBullet's renderer builds each body's look from its
    collision shape with a convex hull, which cost about 0.4 ms per sphere (most of a
    batch spawn); a mesh costs about 0.04 ms.
    """

    def __init__(self, bc: BulletClient) -> None:
        self._create = bc.createCollisionShape
        self._create_visual = bc.createVisualShape
        self._ids: dict[tuple[str, tuple[float, ...]], int] = {}
        self._visual_ids: dict[tuple[str, tuple[float, ...], tuple[float, ...]], int] = {}
        self._mesh_ids: dict[tuple[Any, ...], int] = {}

    def get(self, shape: str, size: tuple[float, ...]) -> int:
        key = (shape, tuple(float(s) for s in size))
        uid = self._ids.get(key)
        if uid is None:
            uid = self._create(**collision_args(shape, key[1]))
            if uid < 0:
                raise OperationFailedError(f"PyBullet could not create a {shape} of size {size}")
            self._ids[key] = uid
        return uid

    def visual(self, shape: str, size: tuple[float, ...],
               rgba: tuple[float, ...] | None) -> int:
        key = (shape, tuple(float(s) for s in size),
               tuple(float(c) for c in (rgba if rgba is not None else WHITE)))
        uid = self._visual_ids.get(key)
        if uid is None:
            vertices, indices = shared_mesh(shape, key[1])
            uid = self._create_visual(pybullet.GEOM_MESH, vertices=vertices, indices=indices,
                                      rgbaColor=list(key[2]))
            if uid < 0:
                raise OperationFailedError(f"PyBullet could not create the look of a {shape}")
            self._visual_ids[key] = uid
        return uid

    def mesh(self, vertices: np.ndarray, faces: np.ndarray, static: bool) -> int:
        """A mesh's collision shape, one per mesh and kind: a static body's collides as its
        triangles (Bullet's concave triangle mesh is for bodies that never move), a moving
        one's as the convex hull of its vertices."""
        key = ("mesh", static, vertices.tobytes(), faces.tobytes())
        uid = self._mesh_ids.get(key)
        if uid is None:
            points = vertices.tolist()
            if static:
                uid = self._create(pybullet.GEOM_MESH, vertices=points,
                                   indices=faces.reshape(-1).tolist())
            else:
                uid = self._create(pybullet.GEOM_MESH, vertices=points)
            if uid < 0:
                raise OperationFailedError("PyBullet could not make a collision mesh of "
                                           f"{len(vertices)} vertices")
            self._mesh_ids[key] = uid
        return uid

    def mesh_visual(self, vertices: np.ndarray, faces: np.ndarray,
                    rgba: tuple[float, ...] | None) -> int:
        colour = tuple(float(c) for c in (rgba if rgba is not None else WHITE))
        key = ("look", colour, vertices.tobytes(), faces.tobytes())
        uid = self._mesh_ids.get(key)
        if uid is None:
            uid = self._create_visual(pybullet.GEOM_MESH, vertices=vertices.tolist(),
                                      indices=faces.reshape(-1).tolist(),
                                      rgbaColor=list(colour))
            if uid < 0:
                raise OperationFailedError("PyBullet could not make the look of a mesh")
            self._mesh_ids[key] = uid
        return uid

    def forget(self) -> None:
        """Drop every id, after resetSimulation has freed the shapes themselves."""
        self._ids.clear()
        self._visual_ids.clear()
        self._mesh_ids.clear()

    def __len__(self) -> int:
        return len(self._ids)


class BodyMaker:
    """Makes and removes rigid bodies, knowing each one's true id.

    createMultiBody(batchPositions=...) returns ids counted back from the last body it
    made, which is right only when ids are handed out in sequence. PyBullet hands out the
    ids of removed bodies first (last removed, first reused), so the holes that deletions
    left are filled one body at a time, the rest comes in one batch, and the batch's ids
    are checked against the positions just given.
    """

    def __init__(self, bc: BulletClient) -> None:
        self._bc = bc
        self._free: set[int] = set()  # ids of removed bodies, which PyBullet reuses first

    def create(self, mass: float, shape: int, visual: int, positions: list[list[float]],
               orientation: list[float], owned: set[int], made: list[int]) -> list[int]:
        """Bodies at these positions, all turned by ``orientation``, appended to ``made`` as
        soon as each exists."""
        def one(position: list[float]) -> int:
            uid = self._bc.createMultiBody(mass, shape, visual, position, orientation,
                                           useMaximalCoordinates=True)
            if uid < 0:
                raise OperationFailedError("PyBullet could not create a body")
            made.append(uid)
            self._free.discard(uid)
            return int(uid)

        holes = min(len(self._free), len(positions))
        ids = [one(position) for position in positions[:holes]]
        rest = positions[holes:]
        if rest:
            batch = self._bc.createMultiBody(mass, shape, visual, rest[0], orientation,
                                             useMaximalCoordinates=True, batchPositions=rest)
            batch = list(batch) if isinstance(batch, tuple | list) else [batch]
            if self._is_true(batch, rest, owned.union(made)):
                made.extend(batch)
                ids.extend(batch)
            else:  # holes it did not know of (a failed load?): find the batch, go slowly
                self._bc.syncBodyInfo()
                self.remove(list(self.known_ids() - owned.union(made)))
                ids.extend(one(position) for position in rest)
        return ids

    def _is_true(self, ids: list[int], positions: list[list[float]], owned: set[int]) -> bool:
        """Whether ``ids`` are new bodies standing exactly where the batch put them."""
        if len(ids) != len(positions) or len(set(ids)) != len(ids) or min(ids) < 0:
            return False
        if any(uid in owned for uid in ids):
            return False
        get_pose, flat = self._bc.getBasePositionAndOrientation, itertools.chain.from_iterable
        try:
            found = np.fromiter(flat(get_pose(uid)[0] for uid in ids), float, 3 * len(ids))
        except pybullet.error:
            return False
        return np.array_equal(found, np.asarray(positions, dtype=float).reshape(-1))

    def remove(self, ids: Sequence[int]) -> None:
        """removeBody each, keeping the freed ids."""
        for uid in ids:
            self._bc.removeBody(uid)
            self._free.add(uid)

    def reused(self, ids: Sequence[int]) -> None:
        """Ids that a model load took (loads return true ids, holes or not)."""
        self._free.difference_update(ids)

    def forget(self) -> None:
        """After resetSimulation: no holes left."""
        self._free.clear()

    def known_ids(self) -> set[int]:
        """Bodies PyBullet's client knows: loads register each, batch spawns do not (until
        syncBodyInfo)."""
        bc = self._bc
        return {bc.getBodyUniqueId(i) for i in range(bc.getNumBodies())}


def read_text(path: str) -> str:
    """A model file's text, read here first so that its XML can be checked."""
    try:
        with open(path, encoding="utf-8") as handle:
            return handle.read()
    except (OSError, UnicodeDecodeError) as exc:
        raise InvalidArgumentError(f"cannot read the model file {path!r}: {exc}") from exc


def check_xml(fmt: str, text: str) -> None:
    """Catch malformed XML here, with its line and column: PyBullet only says it failed."""
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise InvalidArgumentError(
            f"the {fmt.upper()} model is not well-formed XML: {exc}") from exc
    if root.tag != MODEL_ROOTS[fmt]:
        raise InvalidArgumentError(
            f"a {fmt.upper()} model's root element is <{MODEL_ROOTS[fmt]}>, not <{root.tag}>")


@contextmanager
def model_file(fmt: str, text: str) -> Iterator[str]:
    """The text written to a temporary file for PyBullet, a line break between elements
    where a line is long: PyBullet's XML reader fails on lines past about 16 kB."""
    if max(map(len, text.splitlines()), default=0) > LONG_LINE:
        text = text.replace("><", ">\n<")
    with tempfile.TemporaryDirectory(prefix="galton-model-") as folder:
        file_name = os.path.join(folder, "model.urdf" if fmt == "urdf" else "model.xml")
        with open(file_name, "w", encoding="utf-8") as handle:
            handle.write(text)
        yield file_name


def load_bodies(bc: BulletClient, maker: BodyMaker, fmt: str, text: str,
                path: str | None, fixed_base: bool = False) -> list[int]:
    """Load a URDF or MJCF model from its ``text`` (its file names made absolute by the
    daemon; ``path``, where it came from, is not read), a URDF's root welded to the world
    with ``fixed_base``; a model PyBullet refuses leaves no body behind."""
    check_xml(fmt, text)
    wanted = mjcf.plan(text) if fmt == "mjcf" else None  # refuses before anything is made
    before = maker.known_ids()
    try:
        with model_file(fmt, text if wanted is None else wanted.text) as file_name:
            if wanted is None:
                ids = [bc.loadURDF(file_name, useFixedBase=fixed_base, flags=URDF_FLAGS)]
            else:
                ids = list(bc.loadMJCF(file_name, flags=pybullet.MJCF_COLORS_FROM_FILE))
                fix_mjcf_inertia(bc, ids, wanted.text)
                mjcf.apply(bc, ids, wanted)
    except pybullet.error as exc:
        maker.remove(list(maker.known_ids() - before))  # what a half-done load left
        raise InvalidArgumentError(
            f"PyBullet could not load this {fmt.upper()} model ({exc}); its importer "
            "printed the reason on the daemon's output") from exc
    maker.reused(ids)
    return ids


def link_masses(bc: BulletClient, uid: int, links: int) -> tuple[Link, ...]:
    """Mass and inertia diagonal of a loaded body's base and each of its links."""
    infos = (bc.getDynamicsInfo(uid, link) for link in range(-1, links))
    return tuple((float(info[0]), tuple(float(i) for i in info[2])) for info in infos)


def scale_masses(bc: BulletClient, uid: int, links: tuple[Link, ...], mass: float) -> None:
    """Give a loaded body this total mass, its base and links scaled alike from their
    loaded values (as MuJoCo scales a model's subtree), so that repeated updates do not
    compound rounding."""
    factor = mass / max(sum(m for m, _ in links), 1e-12)
    for link, (link_mass, inertia) in zip(range(-1, len(links) - 1), links, strict=True):
        if link_mass > 0:
            bc.changeDynamics(uid, link, mass=link_mass * factor,
                              localInertiaDiagonal=[i * factor for i in inertia])


def unique_name(name: str, taken: set[str]) -> str:
    """``name``, or ``name_1``, ``name_2``... when a body of the same model has it."""
    if name not in taken:
        return name
    return next(f"{name}_{k}" for k in itertools.count(1) if f"{name}_{k}" not in taken)
