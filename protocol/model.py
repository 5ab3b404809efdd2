"""Typed records that travel on the wire, with their checked conversion from msgpack maps.

Conventions: SI units (m, kg, s, rad); a pose is 7 floats ``x y z qx qy qz qw`` (scalar-last
quaternion, as ROS and scipy), a twist 6 floats ``vx vy vz wx wy wz`` in the world frame.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from typing import Any, TypeVar, overload

import msgspec
import numpy as np

from galton.protocol import mesh as mesh_wire
from galton.protocol.arrays import pack_f64, unpack_f64
from galton.protocol.errors import InvalidArgumentError, brief
from galton.protocol.replies import CapabilitiesReply, decode_result
from galton.protocol.status import known_fields, older_defaults, shallow_dict
from galton.protocol.vocabulary import (
    BODY_SHAPES,
    MAX_BATCH,
    MAX_COORDINATE,
    MAX_FORCE,
    MAX_FRICTION,
    MAX_MASS,
    MAX_NAME_LENGTH,
    MAX_TORQUE,
    MAX_TWIST,
    MIN_INERTIA,
    MIN_MASS,
    POSE_WIDTH,
    QUATERNION_NORM_BAND,
    SCALAR_JOINT_TYPES,
    SIZE_LAYOUT,
    TWIST_WIDTH,
    WRENCH_WIDTH,
    SimState,
    check_fields,
)

T = TypeVar("T")


def require(args: dict[str, Any], key: str, kind: type | tuple[type, ...], where: str) -> Any:
    """Fetch a required field, raising InvalidArgument naming it when missing or mistyped."""
    if key not in args:
        raise InvalidArgumentError(f"{where}: missing required field {key!r}")
    return check_type(args[key], kind, f"{where}.{key}")


@overload
def check_type(value: Any, kind: type[T], where: str) -> T: ...
@overload
def check_type(value: Any, kind: tuple[type, ...], where: str) -> Any: ...
def check_type(value: Any, kind: type | tuple[type, ...], where: str) -> Any:
    """``value`` if it is of ``kind`` (a bool is no number), else INVALID_ARGUMENT."""
    if isinstance(value, bool) and kind in (int, float, (int, float)):
        raise InvalidArgumentError(f"{where} must be a number, got a boolean")
    if not isinstance(value, kind):
        names = kind.__name__ if isinstance(kind, type) else " or ".join(k.__name__ for k in kind)
        raise InvalidArgumentError(
            f"{where} must be {names}, got {type(value).__name__} {brief(value)}")
    return value


def finite_number(value: Any, where: str, *, low: float = -math.inf, high: float = math.inf,
                  low_open: bool = False) -> float:
    """A finite float within [low, high] (or (low, high] with low_open), else InvalidArgument."""
    check_type(value, (int, float), where)
    number = float(value)
    too_low = number <= low if low_open else number < low
    if not math.isfinite(number) or too_low or number > high:
        bound = f"({low}, {high}]" if low_open else f"[{low}, {high}]"
        raise InvalidArgumentError(
            f"{where} must be a finite number in {bound}, got {brief(value)}")
    return number


def integer_in(value: Any, where: str, low: int, high: int, unit: str = "") -> int:
    """An integer (not a bool) within [low, high], else InvalidArgument."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InvalidArgumentError(f"{where} must be an integer in [{low}, {high}]{unit}, "
                                   f"got {brief(value)}")
    return value


def optional_number(args: dict[str, Any], key: str, where: str, **bounds: Any) -> float | None:
    value = args.get(key)
    return None if value is None else finite_number(value, f"{where}.{key}", **bounds)


def check_name(value: Any, where: str) -> str:
    name = check_type(value, str, where)
    if not name or len(name) > MAX_NAME_LENGTH or not name.isprintable():
        raise InvalidArgumentError(
            f"{where} {brief(name)} is not a valid entity name: use 1-{MAX_NAME_LENGTH} printable "
            "characters"
        )
    return name


def check_names(value: Any, where: str) -> list[str]:
    """A non-empty list of distinct valid names, at most MAX_BATCH long."""
    check_type(value, list, where)
    if not value:
        raise InvalidArgumentError(f"{where} must name at least one entity")
    if len(value) > MAX_BATCH:
        raise InvalidArgumentError(f"{where} names {len(value)} entities; at most {MAX_BATCH}")
    names = [check_name(n, f"{where}[{i}]") for i, n in enumerate(value)]
    if len(set(names)) != len(names):
        dup = next(n for i, n in enumerate(names) if n in names[:i])
        raise InvalidArgumentError(f"{where} names {brief(dup)} more than once")
    return names


def check_rows(rows: np.ndarray, count: int, width: int, where: str,
               bounds: tuple[tuple[int, int, float, str], ...] = ()) -> np.ndarray:
    """``rows`` if they are ``count`` rows of ``width`` finite numbers, each column run
    ``(start, stop, bound, what)`` of ``bounds`` within +-bound (docs/protocol.md, "Bounds")."""
    if rows.shape != (count, width):
        raise InvalidArgumentError(
            f"{where} holds {rows.shape[0]} rows of {width} numbers; expected {count}"
        )
    if not np.isfinite(rows).all():
        bad = int(np.argwhere(~np.isfinite(rows))[0][0])
        raise InvalidArgumentError(f"{where} row {bad} holds NaN or infinity: {rows[bad].tolist()}")
    for start, stop, bound, what in bounds:
        beyond = np.abs(rows[:, start:stop]) > bound
        if beyond.any():
            row, col = np.argwhere(beyond)[0].tolist()
            raise InvalidArgumentError(
                f"{where} row {row}: {what} {float(rows[row, start + col]):g} is beyond the "
                f"protocol's {what} limit of {bound:g} (docs/protocol.md, \"Bounds\")",
                {"field": where, "max": bound})
    return rows


def quaternion_norms(quaternions: np.ndarray) -> np.ndarray:
    """Each row's norm, without the overflow of squaring a huge component (1e155 squared
    is infinite; a norm of infinity would normalise the quaternion to zero)."""
    scale = np.abs(quaternions).max(axis=1)
    safe = np.where(scale > 0, scale, 1.0)
    norms: np.ndarray = scale * np.linalg.norm(quaternions / safe[:, None], axis=1)
    return norms


def normalise_quaternions(poses: np.ndarray, where: str) -> np.ndarray:
    """Return poses with unit quaternions: each quaternion's norm must lie within
    QUATERNION_NORM_BAND of 1 (a zero, huge or tiny one is refused, naming the row)."""
    low, high = QUATERNION_NORM_BAND
    norms = quaternion_norms(poses[:, 3:7])
    outside = ~((norms >= low) & (norms <= high))
    if outside.any():
        bad = int(np.argmax(outside))
        zero = " (a zero quaternion)" if norms[bad] == 0 else ""
        raise InvalidArgumentError(
            f"{where} row {bad}: the quaternion (qx qy qz qw) {poses[bad, 3:7].tolist()} has "
            f"norm {float(norms[bad]):g}{zero}; its norm must lie in [{low:g}, {high:g}] "
            "(it is normalised within that band)", {"field": where, "row": bad})
    out = poses.copy()
    out[:, 3:7] /= norms[:, None]
    return out


POSE_BOUNDS = ((0, 3, MAX_COORDINATE, "position"),)
TWIST_BOUNDS = ((0, 6, MAX_TWIST, "speed"),)
WRENCH_BOUNDS = ((0, 3, MAX_FORCE, "force"), (3, 6, MAX_TORQUE, "torque"))
POINT_BOUNDS = ((0, 3, MAX_COORDINATE, "position"),)


def decode_poses(data: Any, count: int, where: str) -> np.ndarray:
    rows = check_rows(unpack_f64(data, POSE_WIDTH, where), count, POSE_WIDTH, where,
                      POSE_BOUNDS)
    return normalise_quaternions(rows, where)


def decode_twists(data: Any, count: int, where: str) -> np.ndarray:
    return check_rows(unpack_f64(data, TWIST_WIDTH, where), count, TWIST_WIDTH, where,
                      TWIST_BOUNDS)


def decode_values(data: Any, count: int, where: str, *, bound: float,
                  allow_inf: bool = False) -> np.ndarray:
    """One number per joint: a number (the same for all ``count``) or msgpack bin of
    ``count`` float64; finite and within +-``bound`` (or +inf where ``allow_inf``: an
    effort without a limit)."""
    if isinstance(data, int | float) and not isinstance(data, bool):
        values = np.full(count, float(data))
    else:
        values = unpack_f64(data, 1, where).reshape(-1)
        if values.shape != (count,):
            raise InvalidArgumentError(f"{where} holds {values.shape[0]} numbers; expected "
                                       f"{count} (one per name) or a single number")
    bad = np.isnan(values) | (np.isinf(values) & ~(allow_inf & (values > 0)))
    if bad.any():
        i = int(np.argmax(bad))
        raise InvalidArgumentError(f"{where}[{i}] is {values[i]}: a finite number is needed")
    beyond = np.isfinite(values) & (np.abs(values) > bound)
    if beyond.any():
        i = int(np.argmax(beyond))
        raise InvalidArgumentError(
            f"{where}[{i}] is {values[i]:g}: beyond the protocol's limit of {bound:g} "
            "(docs/protocol.md, \"Bounds\")",
            {"field": where, "max": bound})
    return values


def decode_wrenches(data: Any, count: int, where: str) -> np.ndarray:
    return check_rows(unpack_f64(data, WRENCH_WIDTH, where), count, WRENCH_WIDTH, where,
                      WRENCH_BOUNDS)


def decode_directions(data: Any, count: int, where: str) -> np.ndarray:
    """Direction vectors: finite, of any length (only their direction is used)."""
    return check_rows(unpack_f64(data, 3, where), count, 3, where)


def decode_points(data: Any, count: int, where: str) -> np.ndarray:
    return check_rows(unpack_f64(data, 3, where), count, 3, where, POINT_BOUNDS)


def check_tags(value: Any, where: str) -> tuple[str, ...]:
    check_type(value, list, where)
    return tuple(check_name(t, f"{where}[{i}]") for i, t in enumerate(value))


def check_rgba(value: Any, where: str) -> tuple[float, float, float, float] | None:
    if value is None:
        return None
    check_type(value, list, where)
    if len(value) != 4:
        raise InvalidArgumentError(f"{where} must hold 4 numbers (r g b a in 0..1)")
    r, g, b, a = (finite_number(v, f"{where}[{i}]", low=0, high=1) for i, v in enumerate(value))
    return (r, g, b, a)


@dataclass
class BodyProperties:
    """Properties that ``update`` may change; None leaves a property as it is."""

    mass: float | None = None
    friction: float | None = None
    restitution: float | None = None
    rgba: tuple[float, float, float, float] | None = None
    tags: tuple[str, ...] | None = None

    def to_wire(self) -> dict[str, Any]:
        return {k: (list(v) if isinstance(v, tuple) else v)
                for k, v in asdict(self).items() if v is not None}

    @classmethod
    def from_wire(cls, args: dict[str, Any], where: str = "properties") -> BodyProperties:
        check_type(args, dict, where)
        check_fields(args, ("mass", "friction", "restitution", "rgba", "tags"), where)
        tags = args.get("tags")
        return cls(
            mass=optional_number(args, "mass", where, low=MIN_MASS, high=MAX_MASS),
            friction=optional_number(args, "friction", where, low=0, high=MAX_FRICTION),
            restitution=optional_number(args, "restitution", where, low=0, high=1),
            rgba=check_rgba(args.get("rgba"), f"{where}.rgba"),
            tags=None if tags is None else check_tags(tags, f"{where}.tags"),
        )


@dataclass
class BodyGroup:
    """Bodies of one shape and material spawned together; each has its own name and state."""

    shape: str
    size: tuple[float, ...]
    names: list[str]
    poses: np.ndarray
    twists: np.ndarray | None = None
    static: bool = False
    mass: float | None = None
    friction: float | None = None
    restitution: float | None = None
    rgba: tuple[float, float, float, float] | None = None
    tags: tuple[str, ...] = ()
    # A mesh's triangles in the body's frame: (n, 3) float64 vertices, (m, 3) int faces.
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    # A diagonal inertia (kg m², about the body's centre of mass) in place of the shape's.
    inertia: tuple[float, float, float] | None = None

    def __len__(self) -> int:
        return len(self.names)

    def to_wire(self) -> dict[str, Any]:
        out = self._core_wire()
        if self.vertices is not None and self.faces is not None:
            out["size"] = []
            out["vertices"] = mesh_wire.pack_vertices(self.vertices)
            out["faces"] = mesh_wire.pack_faces(self.faces)
        if self.inertia is not None:
            out["inertia"] = [float(v) for v in self.inertia]
        return out

    def _core_wire(self) -> dict[str, Any]:
        return {
            "shape": self.shape,
            "size": [float(s) for s in self.size],
            "names": list(self.names),
            "poses": pack_f64(np.asarray(self.poses, dtype=float).reshape(-1, POSE_WIDTH)),
            "twists": None if self.twists is None else pack_f64(
                np.asarray(self.twists, dtype=float).reshape(-1, TWIST_WIDTH)),
            "static": self.static,
            "mass": self.mass,
            "friction": self.friction,
            "restitution": self.restitution,
            "rgba": None if self.rgba is None else list(self.rgba),
            "tags": list(self.tags),
        }

    @classmethod
    def from_wire(cls, body: Any, where: str = "group") -> BodyGroup:
        check_type(body, dict, where)
        check_fields(body, GROUP_FIELDS, where)
        shape = require(body, "shape", str, where)
        if shape not in BODY_SHAPES:
            raise InvalidArgumentError(
                f"{where}.shape {brief(shape)} is not one of {', '.join(BODY_SHAPES)}")
        vertices, faces = _check_mesh(shape, body, where)
        size: tuple[float, ...]
        if vertices is not None:
            size = mesh_wire.half_extents(vertices)
        else:
            size = _check_size(shape, require(body, "size", list, where), f"{where}.size")
        names = check_names(require(body, "names", list, where), f"{where}.names")
        poses = decode_poses(require(body, "poses", (bytes, bytearray), where), len(names),
                             f"{where}.poses")
        twists_raw = body.get("twists")
        twists = None if twists_raw is None else decode_twists(twists_raw, len(names),
                                                               f"{where}.twists")
        static = check_type(body.get("static", False), bool, f"{where}.static")
        if shape == "plane" and not static:
            raise InvalidArgumentError(f"{where}: a plane must be static (set static: true)")
        if static and twists is not None and np.any(twists):
            raise InvalidArgumentError(f"{where}: static bodies cannot have a non-zero twist")
        return cls(
            shape=shape, size=size, names=names, poses=poses, twists=twists, static=static,
            mass=optional_number(body, "mass", where, low=MIN_MASS, high=MAX_MASS),
            friction=optional_number(body, "friction", where, low=0, high=MAX_FRICTION),
            restitution=optional_number(body, "restitution", where, low=0, high=1),
            rgba=check_rgba(body.get("rgba"), f"{where}.rgba"),
            tags=check_tags(body.get("tags", []), f"{where}.tags"),
            vertices=vertices, faces=faces,
            inertia=_check_inertia(body.get("inertia"), static, f"{where}.inertia"),
        )


GROUP_FIELDS = ("shape", "size", "names", "poses", "twists", "static", "mass", "friction",
                "restitution", "rgba", "tags", "vertices", "faces", "inertia")


def _check_mesh(shape: str, body: dict[str, Any], where: str
                ) -> tuple[np.ndarray | None, np.ndarray | None]:
    """A mesh group's vertices and faces, checked; none for the other shapes."""
    if shape != "mesh":
        for key in ("vertices", "faces"):
            if body.get(key) is not None:
                raise InvalidArgumentError(f"{where}.{key} is for a mesh, not a {shape}")
        return None, None
    if body.get("size") not in (None, []):
        raise InvalidArgumentError(f"{where}.size must be left out for a mesh (its size is "
                                   f"its vertices' reach), got {brief(body.get('size'))}")
    vertices = mesh_wire.decode_vertices(require(body, "vertices", (bytes, bytearray), where),
                                         f"{where}.vertices")
    faces = mesh_wire.decode_faces(require(body, "faces", (bytes, bytearray), where),
                                   len(vertices), f"{where}.faces")
    mesh_wire.check_area(vertices, faces, where)
    return vertices, faces


def _check_inertia(value: Any, static: bool, where: str) -> tuple[float, float, float] | None:
    """Three positive principal moments (kg m²); a static body has none to override."""
    if value is None:
        return None
    check_type(value, list, where)
    if len(value) != 3:
        raise InvalidArgumentError(f"{where} must hold 3 numbers (ixx iyy izz, kg m²), "
                                   f"got {len(value)}")
    if static:
        raise InvalidArgumentError(f"{where}: a static body has no inertia to set")
    ixx, iyy, izz = (finite_number(v, f"{where}[{i}]", low=MIN_INERTIA, high=MAX_MASS)
                     for i, v in enumerate(value))
    if ixx + iyy < izz or iyy + izz < ixx or ixx + izz < iyy:
        raise InvalidArgumentError(f"{where} {[ixx, iyy, izz]} breaks the triangle "
                                   "inequality no rigid body's principal moments break")
    return (ixx, iyy, izz)




def _check_size(shape: str, size: list[Any], where: str) -> tuple[float, ...]:
    layout = SIZE_LAYOUT[shape]
    if len(size) != len(layout):
        raise InvalidArgumentError(
            f"{where} for a {shape} must hold {len(layout)} numbers ({', '.join(layout)}), "
            f"got {len(size)}"
        )
    return tuple(finite_number(v, f"{where}[{i}] ({layout[i]})", low=0, low_open=True, high=1e4)
                 for i, v in enumerate(size))


@dataclass
class EntityInfo:
    """What the scene graph knows of one entity."""

    name: str
    shape: str
    size: tuple[float, ...] = ()
    static: bool = False
    tags: tuple[str, ...] = ()
    mass: float | None = None
    friction: float | None = None
    restitution: float | None = None
    source: str = "spawn"
    model: str | None = None  # a loaded model's root entity, for the root and its links

    def to_wire(self) -> dict[str, Any]:
        out = asdict(self)
        out["size"] = list(self.size)
        out["tags"] = list(self.tags)
        return out

    @classmethod
    def from_wire(cls, body: dict[str, Any]) -> EntityInfo:
        return cls(**{**known_fields(cls, body), "size": tuple(body.get("size", ())),
                      "tags": tuple(body.get("tags", ()))})


@dataclass
class JointInfo:
    """One joint of a loaded model (docs/protocol.md, "joints")."""

    name: str
    model: str
    type: str  # one of JOINT_TYPES
    parent: str  # parent link entity ("" for a root's free joint)
    child: str  # child link entity
    axis: tuple[float, float, float] = (0.0, 0.0, 0.0)  # unit, in the child link's frame
    lower: float | None = None  # rad or m; None when unlimited
    upper: float | None = None
    damping: float = 0.0
    effort_limit: float | None = None
    velocity_limit: float | None = None
    mode: str = "none"  # the target mode now held, one of TARGET_MODES

    @property
    def scalar(self) -> bool:
        """Whether it has one degree of freedom (states and targets address it)."""
        return self.type in SCALAR_JOINT_TYPES

    def to_wire(self) -> dict[str, Any]:
        out = asdict(self)
        out["axis"] = list(self.axis)
        return out

    @classmethod
    def from_wire(cls, body: dict[str, Any]) -> JointInfo:
        axis = body.get("axis", (0.0, 0.0, 0.0))
        return cls(**{**known_fields(cls, body),
                      "axis": (float(axis[0]), float(axis[1]), float(axis[2]))})


@dataclass
class Telemetry:
    """One telemetry sample, published at the daemon's telemetry rate."""

    seq: int
    instance: str
    engine: str
    state: SimState
    step: int
    sim_time: float
    wall_time: float
    rtf: float
    target_rtf: float
    timestep: float
    entity_count: int
    cpu_percent: float
    rss_bytes: int
    peak_rss_bytes: int
    world: str = "default"

    def to_wire(self) -> dict[str, Any]:
        return shallow_dict(self)

    @classmethod
    def from_wire(cls, body: dict[str, Any]) -> Telemetry:
        return cls(**{**known_fields(cls, body), "state": SimState(body["state"])})


@dataclass
class Capabilities:
    """What an engine can do; anything it cannot do is refused with FEATURE_UNSUPPORTED."""

    engine: str
    engine_version: str
    protocol_version: int
    body_shapes: tuple[str, ...]
    model_formats: tuple[str, ...]
    features: tuple[str, ...]
    params: dict[str, dict[str, Any]] = field(default_factory=dict)
    engines_available: tuple[str, ...] = ()
    render_backend: str | None = None  # how it renders headless (egl, osmesa, tinyrenderer)
    # The daemon's ZeroMQ endpoints ("control" and "telemetry" lists, "server_key" when
    # encrypted), {} without --zmq.
    zmq: dict[str, Any] = field(default_factory=dict)
    # The daemon's machine (CPU, cores, memory, OS, versions), {} from an older daemon.
    host: dict[str, Any] = field(default_factory=dict)

    def supports(self, feature: str) -> bool:
        return feature in self.features

    def to_wire(self) -> dict[str, Any]:
        out = asdict(self)
        for key in ("body_shapes", "model_formats", "features", "engines_available"):
            out[key] = list(out[key])
        return out

    @classmethod
    def from_wire(cls, body: dict[str, Any]) -> Capabilities:
        """Parse a reply through its declaration; fields this client does not know (a newer
        daemon's) are left out, and ``host`` may be absent (an older daemon's)."""
        caps = msgspec.structs.asdict(
            decode_result(CapabilitiesReply, {**older_defaults(cls), **body}))
        return cls(**{**caps, **{k: tuple(caps[k]) for k in (
            "body_shapes", "model_formats", "features", "engines_available")}})
