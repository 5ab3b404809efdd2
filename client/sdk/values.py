"""What SDK calls return beyond the protocol's records: stamps, body and joint states,
images, ray hits and contacts.

Each value is built from the reply that carried it, so a value never mixes one request's
numbers with another's (a Client may be used from several threads at once), and through
its operation's declared reply type (protocol/replies.py): a reply that does not fit is
MalformedRequestError, a field a newer daemon added is left out.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from galton.protocol import POSE_WIDTH, TWIST_WIDTH, OperationFailedError, Reply, unpack_f64
from galton.protocol import replies as rp
from galton.protocol.png import decode_png
from galton.protocol.replies import ShapesReply

FloatArray = NDArray[np.float64]
MM = 1000.0  # depth PNGs hold millimetres


@dataclass(frozen=True)
class Stamp:
    """The step and sim time at which a request took effect (every reply carries them)."""

    step: int
    sim_time: float

    @classmethod
    def of(cls, reply: Reply) -> Stamp:
        return cls(reply.step, reply.sim_time)


@dataclass
class States:
    """Poses (n, 7: x y z qx qy qz qw) and world twists (n, 6) of named bodies, at the step
    and sim time of the reply that carried them."""

    names: list[str]
    poses: FloatArray
    twists: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> States:
        """The states a ``get_states`` or reading step reply holds, stamped by it."""
        result = rp.decode_result(rp.StatesReply, reply.result)
        return cls(result.names, unpack_f64(result.poses, POSE_WIDTH, "poses"),
                   unpack_f64(result.twists, TWIST_WIDTH, "twists"), reply.step,
                   reply.sim_time)

    @property
    def stamp(self) -> Stamp:
        return Stamp(self.step, self.sim_time)

    @property
    def positions(self) -> FloatArray:
        return self.poses[:, :3]

    @property
    def speeds(self) -> FloatArray:
        return np.asarray(np.linalg.norm(self.twists[:, :3], axis=1), dtype=np.float64)


@dataclass
class JointStates:
    """Positions, velocities and efforts (each (n,) float64) of named one-degree-of-freedom
    joints, at the step and sim time of the reply that carried them. Units: rad, rad/s,
    N·m for revolute joints; m, m/s, N for prismatic ones. ``efforts`` is what each joint's
    target applied in the last step (0 in mode "none")."""

    names: list[str]
    positions: FloatArray
    velocities: FloatArray
    efforts: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> JointStates:
        """The joint states of a ``get_joint_states`` reply."""
        return cls.from_result(reply.result, reply)

    @classmethod
    def from_step_reply(cls, reply: Reply) -> JointStates:
        """The joint states a ``step`` or ``run_until`` with ``read_joints`` carries."""
        return cls.from_result(reply.result["joints"], reply)

    @classmethod
    def from_result(cls, result: dict[str, Any], reply: Reply) -> JointStates:
        states = rp.decode_result(rp.JointStatesReply, result)
        return cls(states.names, _column(states.positions, "positions"),
                   _column(states.velocities, "velocities"), _column(states.efforts, "efforts"),
                   reply.step, reply.sim_time)

    @property
    def stamp(self) -> Stamp:
        return Stamp(self.step, self.sim_time)

    def __len__(self) -> int:
        return len(self.names)


def _column(data: bytes, key: str) -> FloatArray:
    return unpack_f64(data, 1, key)[:, 0]


# -- worlds, snapshots, predictions, comparisons (issue 25) ------------------------------
@dataclass(frozen=True)
class WorldInfo:
    """One world of a daemon, as ``list_worlds`` describes it: the live one plays, side
    worlds move only when stepped."""

    name: str
    live: bool
    engine: str
    state: str
    step: int
    sim_time: float
    entity_count: int
    faulted: bool

    @classmethod
    def from_wire(cls, row: dict[str, Any]) -> WorldInfo:
        return cls.of(rp.decode_result(rp.WorldReply, row))

    @classmethod
    def of(cls, world: rp.WorldReply) -> WorldInfo:
        return cls(world.name, world.live, world.engine, world.state, world.step,
                   world.sim_time, world.entity_count, world.faulted)


@dataclass(frozen=True)
class SnapshotInfo:
    """A snapshot: the slot keeping it (None when only its bytes were asked for), its world
    and engine, its size (``nbytes``, the wire's ``bytes``), and the step it was taken at;
    ``blob`` holds its bytes when asked (any daemon with the same engine restores it)."""

    slot: str | None
    world: str
    engine: str
    nbytes: int
    step: int
    sim_time: float
    entity_count: int
    blob: bytes | None = None

    @classmethod
    def from_wire(cls, row: dict[str, Any], world: str = "", engine: str = "") -> SnapshotInfo:
        """A ``snapshots`` row, or a ``snapshot`` result (an older daemon's named neither
        world nor engine: ``world`` and ``engine`` stand in for them)."""
        info = rp.decode_result(rp.SnapshotReply, {"world": world, "engine": engine, **row})
        return cls(info.slot, info.world, info.engine, info.bytes, info.step, info.sim_time,
                   info.entity_count, info.blob)


@dataclass
class Prediction:
    """What ``predict`` sampled on discarded copies of a world: ``times`` (samples,) from
    the world's sim time, the present first; ``poses`` (samples, bodies, 7) and ``twists``
    (samples, bodies, 6) of ``names``; ``joint_positions`` and ``joint_velocities``
    (samples, joints) of ``joint_names``. With ``futures`` > 1 each of those gains a
    leading futures axis, ``spread`` (samples, bodies) is the standard deviation of each
    body's position across futures (m), ``seed`` the perturbation's; ``scores``
    (futures,) with a score. Stamped with the world's present."""

    times: FloatArray
    steps: int
    names: list[str]
    poses: FloatArray
    twists: FloatArray
    joint_names: list[str]
    joint_positions: FloatArray
    joint_velocities: FloatArray
    step: int
    sim_time: float
    futures: int = 1
    spread: FloatArray | None = None
    scores: FloatArray | None = None
    seed: int | None = None

    @classmethod
    def from_reply(cls, reply: Reply) -> Prediction:
        result = rp.decode_result(rp.PredictReply, reply.result)
        times = _column(result.times, "times")
        samples = len(times)
        count = result.futures
        names = result.names or []
        joints = result.joints or rp.JointSamples(names=[], positions=b"", velocities=b"")
        joint_names = joints.names

        def rows(data: bytes | None, width: int, key: str, many: int) -> FloatArray:
            out = _samples(data, count * samples, many, width, key)
            return out.reshape(count, samples, many, width) if count > 1 else out
        spread = None if result.spread is None else unpack_f64(
            result.spread, max(len(names), 1), "spread").reshape(samples, len(names))
        return cls(times, result.steps, names,
                   rows(result.poses, POSE_WIDTH, "poses", len(names)),
                   rows(result.twists, TWIST_WIDTH, "twists", len(names)),
                   joint_names,
                   rows(joints.positions, 1, "positions", len(joint_names))[..., 0],
                   rows(joints.velocities, 1, "velocities", len(joint_names))[..., 0],
                   reply.step, reply.sim_time, count, spread,
                   None if result.scores is None else _column(result.scores, "scores"),
                   result.seed)

    def __len__(self) -> int:
        return len(self.times)

    def spread_of(self, names: Sequence[str], sample: int = -1) -> FloatArray:
        """The spread of these bodies' positions at one sample (the horizon by default),
        as ``compare(..., spread=...)`` takes it; zeros for a single future."""
        if self.spread is None:
            return np.zeros(len(names))
        return self.spread[sample, [self.names.index(n) for n in names]]

    def at(self, name: str) -> FloatArray:
        """The poses (samples, 7) of one body along the prediction ((futures, samples, 7)
        with futures)."""
        return self.poses[..., self.names.index(name), :]


def _samples(data: bytes | None, samples: int, count: int, width: int, key: str
             ) -> FloatArray:
    """Rows of ``width`` sample after sample, as (samples, count, width); empty if absent."""
    if data is None or count == 0:
        return np.zeros((samples, count, width))
    return unpack_f64(data, width, key).reshape(samples, count, width)


@dataclass
class Comparison:
    """Observed poses against the world's: per body the position error (m), the angle of
    the rotation between the orientations (rad), the speed error (m/s, when twists were
    given, else None), and the anomaly score, the RMS over bodies of the errors divided by
    their sigmas (about 1 at the stated noise; above 3 is a surprise)."""

    names: list[str]
    position_errors: FloatArray
    angle_errors: FloatArray
    speed_errors: FloatArray | None
    score: float
    corrected: bool
    step: int
    sim_time: float
    streak: int | None = None  # with a trigger: surprising comparisons in a row
    suggested: bool = False  # with a trigger: this one made the streak its window
    calibrating: bool = False  # with a trigger's calibrate: this one started it

    @classmethod
    def from_reply(cls, reply: Reply, names: list[str]) -> Comparison:
        result = rp.decode_result(rp.CompareReply, reply.result)
        speeds = result.speed_errors
        return cls(names, _column(result.position_errors, "position_errors"),
                   _column(result.angle_errors, "angle_errors"),
                   None if speeds is None else _column(speeds, "speed_errors"),
                   result.score, result.corrected, reply.step, reply.sim_time,
                   result.streak, bool(result.suggested), bool(result.calibrating))


# -- perception (issue 26) ----------------------------------------------------------------
@dataclass
class Image:
    """One camera's picture, rows top first: ``rgb`` (h, w, 3) uint8, ``depth`` (h, w)
    float32 metres along the view axis (+inf: nothing within ``far``), ``segmentation``
    (h, w) int32 indices into ``labels`` (-1: nothing); an output not asked for is None.
    Stamped with the step it shows."""

    width: int
    height: int
    rgb: NDArray[np.uint8] | None
    depth: NDArray[np.float32] | None
    segmentation: NDArray[np.int32] | None
    labels: list[str]
    step: int
    sim_time: float

    @classmethod
    def from_wire(cls, image: dict[str, Any], labels: list[str], fmt: str,
                  reply: Reply) -> Image:
        """One entry of a ``render`` result, raw or PNG."""
        width, height = int(image["width"]), int(image["height"])
        shape = (height, width)
        rgb = depth = segmentation = None
        if "rgb" in image:
            rgb = _rgb(image["rgb"], fmt, shape)
        if "depth" in image:
            depth = _depth(image["depth"], fmt, shape)
        if "segmentation" in image:
            segmentation = _segmentation(image["segmentation"], fmt, shape)
        return cls(width, height, rgb, depth, segmentation, labels, reply.step,
                   reply.sim_time)

    def label_at(self, row: int, column: int) -> str | None:
        """The entity seen at one pixel (None: nothing there)."""
        if self.segmentation is None:
            raise OperationFailedError("this image has no segmentation; ask for it in "
                                       "the camera's outputs")
        index = int(self.segmentation[row, column])
        return None if index < 0 else self.labels[index]

    def mask(self, name: str) -> NDArray[np.bool_]:
        """The pixels showing entity ``name`` (all False when it is not seen)."""
        if self.segmentation is None:
            raise OperationFailedError("this image has no segmentation; ask for it in "
                                       "the camera's outputs")
        if name not in self.labels:
            return np.zeros(self.segmentation.shape, dtype=bool)
        return np.asarray(self.segmentation == self.labels.index(name))


def _checked(pixels: np.ndarray, shape: tuple[int, ...], kind: str) -> np.ndarray:
    if pixels.size != int(np.prod(shape)):
        raise OperationFailedError(f"a rendered {kind} holds {pixels.size} values, expected "
                                   f"{int(np.prod(shape))} for {shape}")
    return pixels.reshape(shape)


def _rgb(data: bytes, fmt: str, shape: tuple[int, int]) -> NDArray[np.uint8]:
    pixels = decode_png(data) if fmt == "png" else np.frombuffer(data, np.uint8)
    return np.array(_checked(pixels, (*shape, 3), "rgb"), dtype=np.uint8)


def _depth(data: bytes, fmt: str, shape: tuple[int, int]) -> NDArray[np.float32]:
    if fmt != "png":
        return np.array(_checked(np.frombuffer(data, "<f4"), shape, "depth"), np.float32)
    millimetres = _checked(decode_png(data), shape, "depth").astype(np.float32)
    return np.where(millimetres == 0, np.float32(np.inf), millimetres / np.float32(MM))


def _segmentation(data: bytes, fmt: str, shape: tuple[int, int]) -> NDArray[np.int32]:
    if fmt != "png":
        return np.array(_checked(np.frombuffer(data, "<i4"), shape, "segmentation"),
                        np.int32)
    return _checked(decode_png(data), shape, "segmentation").astype(np.int32) - 1


@dataclass
class RayHits:
    """One entry per ray: ``hits`` (n,) bool; ``entities`` the entity hit ("" for a miss);
    ``points`` and ``normals`` (n, 3) world frame and ``distances`` (n,) metres from the
    origin, NaN for a miss."""

    hits: NDArray[np.bool_]
    entities: list[str]
    points: FloatArray
    normals: FloatArray
    distances: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> RayHits:
        result = rp.decode_result(rp.RaycastReply, reply.result)
        return cls(np.frombuffer(result.hits, np.uint8).astype(bool), result.entities,
                   unpack_f64(result.points, 3), unpack_f64(result.normals, 3),
                   _column(result.distances, "distances"), reply.step, reply.sim_time)

    def __len__(self) -> int:
        return len(self.entities)


@dataclass
class Contacts:
    """The contact points of the last step: entities ``a`` and ``b`` of each, ``positions``
    and ``normals`` (n, 3, world frame; a normal points from a to b), ``forces`` (n,) the
    normal force in N, ``penetrations`` (n,) in m."""

    a: list[str]
    b: list[str]
    positions: FloatArray
    normals: FloatArray
    forces: FloatArray
    penetrations: FloatArray
    step: int
    sim_time: float

    @classmethod
    def from_reply(cls, reply: Reply) -> Contacts:
        result = rp.decode_result(rp.ContactsReply, reply.result)
        return cls(result.a, result.b, unpack_f64(result.positions, 3),
                   unpack_f64(result.normals, 3), _column(result.forces, "forces"),
                   _column(result.penetrations, "penetrations"), reply.step, reply.sim_time)

    def __len__(self) -> int:
        return len(self.a)

    def between(self, first: str, second: str) -> NDArray[np.bool_]:
        """Which contacts join ``first`` and ``second`` (either way round)."""
        return np.array([{x, y} == {first, second} for x, y in zip(self.a, self.b,
                                                                   strict=True)], dtype=bool)


@dataclass(frozen=True)
class ShapeInfo:
    """One collision shape of an entity (``get_shapes``): kind (a body shape or "mesh"),
    half sizes as the protocol's SIZE_LAYOUT (a mesh: a box around it), pose (7) in the
    entity's frame; a mesh's triangles in that pose's frame where the daemon tells them
    (``vertices`` (n, 3), ``faces`` (m, 3) indices; shapes of one mesh share the arrays)."""

    kind: str
    size: tuple[float, ...]
    pose: FloatArray
    vertices: FloatArray | None = None
    faces: NDArray[np.int64] | None = None

    @property
    def boxed(self) -> bool:
        """A mesh told only as the box around it: the daemon knows no triangles of it."""
        return self.kind == "mesh" and self.vertices is None


Triangles = tuple[FloatArray, NDArray[np.int64]]  # a mesh's vertices and faces


def shapes_of(reply: ShapesReply) -> dict[str, list[ShapeInfo]]:
    """A ``get_shapes`` reply's flat rows grouped by entity, meshes with their triangles."""
    if len(reply.mesh_vertices) != len(reply.mesh_faces):
        raise OperationFailedError("get_shapes: mesh_vertices and mesh_faces disagree")
    table = [triangles_of(unpack_f64(v, 3, "mesh_vertices"), np.frombuffer(f, dtype="<u4"))
             for v, f in zip(reply.mesh_vertices, reply.mesh_faces, strict=True)]
    return grouped_shapes(reply.names, reply.counts, reply.kinds,
                          unpack_f64(reply.sizes, 3, "sizes"),
                          unpack_f64(reply.poses, POSE_WIDTH, "poses"), reply.meshes, table)


def triangles_of(vertices: NDArray[Any], faces: NDArray[Any]) -> Triangles:
    """A mesh's (n, 3) vertices and (m, 3) faces, whose indices must name its vertices."""
    rows = np.asarray(faces, dtype=np.int64).reshape(-1, 3) if np.size(faces) % 3 == 0 \
        else None
    if rows is None or (rows.size and (rows.min() < 0 or rows.max() >= len(vertices))):
        raise OperationFailedError("get_shapes: a mesh's faces do not index its vertices")
    return np.asarray(vertices, dtype=np.float64).reshape(-1, 3), rows


def grouped_shapes(names: list[str], counts: list[int], kinds: list[str],
                   size_rows: FloatArray, pose_rows: FloatArray, meshes: list[int],
                   table: list[Triangles]) -> dict[str, list[ShapeInfo]]:
    """Flat shape rows (as ``get_shapes`` sends them) grouped by entity; ``meshes``: each
    row's index into ``table`` (-1: none), or empty where no row has one."""
    rows = len(kinds)
    if sum(counts) != rows or rows != len(size_rows) or rows != len(pose_rows) \
            or len(names) != len(counts) or (meshes and len(meshes) != rows) \
            or any(not -1 <= index < len(table) for index in meshes):
        raise OperationFailedError("get_shapes: counts, kinds, sizes, poses and meshes "
                                   "disagree")
    mesh_of = [table[i] if i >= 0 else None for i in meshes] or [None] * rows
    found: dict[str, list[ShapeInfo]] = {}
    start = 0
    for name, count in zip(names, counts, strict=True):
        found[name] = [ShapeInfo(kinds[i], tuple(float(v) for v in size_rows[i]), pose_rows[i],
                                 *(mesh_of[i] or (None, None)))
                       for i in range(start, start + count)]
        start += count
    return found
