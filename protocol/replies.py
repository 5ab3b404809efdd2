"""Every operation's reply, declared once as a msgspec Struct: the fields of its ``result``
map (docs/protocol.md describes each beside its operation).

protocol/operations.py names each operation's reply type; ``galton-client schema`` prints
them as JSON Schema; the SDK decodes replies with them (``decode_result``), and the
conformance suite holds every reply the daemon gives to its declaration, exactly: no field
missing, none extra. A field that is ``None`` by default is one the daemon leaves out
unless the request asked for it.

The daemon builds its replies as plain maps and does not convert them through these types:
converting costs more than the reply it checks (docs/PERFORMANCE.md, "Replies").
"""

from __future__ import annotations

from typing import Annotated, Any, Literal, TypeVar

import msgspec

from galton.protocol.errors import MalformedRequestError

R = TypeVar("R", bound="Reply")


def _rows(width: int, what: str = "") -> msgspec.Meta:
    return msgspec.Meta(description=f"packed float64 rows, {width} wide{what}")


Poses = Annotated[bytes, _rows(7)]
Twists = Annotated[bytes, _rows(6)]
Vectors = Annotated[bytes, _rows(3)]
Numbers = Annotated[bytes, msgspec.Meta(description="packed float64, one per row")]
Blob = bytes  # a field named `bytes` below shadows the type in its class


class Reply(msgspec.Struct, kw_only=True):
    """A reply's ``result`` map (or a row of one). A field it does not declare is left out
    when the SDK decodes (a newer daemon's reply that grew, as ``status`` grew
    ``controller``); the conformance suite refuses one (``decode_result(exact=True)``)."""


# -- shared by several operations -----------------------------------------------------------


class StatusReply(Reply, kw_only=True):
    """A world's clock and state (``status``, and what time control answers)."""

    state: Literal["stopped", "playing", "paused"]
    step: int
    sim_time: float
    timestep: float
    target_rtf: float
    rtf: float
    entity_count: int
    engine: str
    instance: str
    world: str
    faulted: bool
    controller: str | None
    stepping: bool = False  # a step request runs on the live world now (absent: older daemon)


class CountReply(Reply, kw_only=True):
    count: int


class NamesReply(Reply, kw_only=True):
    names: list[str]


class ParamsReply(Reply, kw_only=True):
    params: dict[str, Any]


class WorldReply(Reply, kw_only=True):
    """One world (``list_worlds``' rows; what create_world, fork_world and restore answer)."""

    name: str
    live: bool
    engine: str
    state: Literal["stopped", "playing", "paused"]
    step: int
    sim_time: float
    entity_count: int
    faulted: bool


class JointSamples(Reply, kw_only=True):
    """Joint positions and velocities read back by a step request or a prediction."""

    names: list[str]
    positions: Numbers
    velocities: Numbers


class JointStatesReply(JointSamples, kw_only=True):
    """``get_joint_states``: the samples' fields and each joint's effort."""

    efforts: Numbers


# -- one operation each ---------------------------------------------------------------------


class CapabilitiesReply(Reply, kw_only=True):
    engine: str
    engine_version: str
    protocol_version: int
    body_shapes: list[str]
    model_formats: list[str]
    features: list[str]
    params: dict[str, dict[str, Any]]
    engines_available: list[str]
    render_backend: str | None
    zmq: dict[str, Any]
    host: dict[str, Any]


class EntitiesReply(Reply, kw_only=True):
    entities: list[dict[str, Any]]


class StatesReply(Reply, kw_only=True):
    names: list[str]
    poses: Poses
    twists: Twists


class BoundsReply(Reply, kw_only=True):
    names: list[str]
    bounds: Annotated[bytes, _rows(6, ": min x y z, max x y z")]


class ShapesReply(Reply, kw_only=True):
    """Each entity's collision shapes, flat: ``counts[i]`` rows belong to ``names[i]``."""

    names: list[str]
    counts: list[int]
    kinds: list[str]
    sizes: Annotated[bytes, _rows(3, ": half sizes as SIZE_LAYOUT, zero padded")]
    poses: Annotated[bytes, _rows(7, ": each shape's pose in its entity's frame")]
    # Sent only when some row is a ``mesh`` (a reply without one is as before meshes were
    # told): per row, its index into ``mesh_vertices`` / ``mesh_faces``, -1 for a primitive
    # or for a mesh the daemon knows only as its box. Rows of one mesh share one index.
    meshes: list[int] = msgspec.field(default_factory=list)
    mesh_vertices: list[Annotated[bytes, _rows(3, ": in its row's frame")]] = \
        msgspec.field(default_factory=list)
    mesh_faces: list[Annotated[bytes, msgspec.Meta(
        description="packed uint32 rows, 3 wide: vertex indices")]] = \
        msgspec.field(default_factory=list)


class StepReply(Reply, kw_only=True):
    """What ``step`` and ``run_until`` answer when their steps are done."""

    steps: int
    names: list[str] | None = None
    poses: Poses | None = None
    twists: Twists | None = None
    at_rest: bool | None = None
    joints: JointStatesReply | None = None


class JointsReply(Reply, kw_only=True):
    joints: list[dict[str, Any]]


class SetJointStatesReply(Reply, kw_only=True):
    count: int
    names: list[str] | None = None
    poses: Poses | None = None
    twists: Twists | None = None


class SnapshotFacts(Reply, kw_only=True):
    """What a snapshot says of itself, in its reply and in a slot's row."""

    world: str
    engine: str
    bytes: int
    step: int
    sim_time: float
    entity_count: int


class SnapshotReply(SnapshotFacts, kw_only=True):
    slot: str | None
    blob: Blob | None = None


class SlotRow(SnapshotFacts, kw_only=True):
    slot: str


class SnapshotsReply(Reply, kw_only=True):
    slots: list[SlotRow]


class WorldsReply(Reply, kw_only=True):
    worlds: list[WorldReply]


class PredictReply(Reply, kw_only=True):
    steps: int
    times: Numbers
    names: list[str] | None = None
    poses: Poses | None = None
    twists: Twists | None = None
    joints: JointSamples | None = None
    futures: int = 1  # > 1: poses, twists and joints future after future
    spread: Numbers | None = None  # futures > 1: (samples, bodies) std of position, m
    scores: Numbers | None = None  # with a score: one per future
    seed: int | None = None  # the seed the perturbation was drawn with


class CompareReply(Reply, kw_only=True):
    position_errors: Numbers
    angle_errors: Numbers
    speed_errors: Numbers | None = None
    score: float
    corrected: bool
    streak: int | None = None  # with a trigger: surprising comparisons in a row, this one's
    suggested: bool | None = None  # with a trigger: this one made the streak its window
    calibrating: bool | None = None  # with a trigger's calibrate, when suggested: started


class RenderReply(Reply, kw_only=True):
    images: list[dict[str, Any]]
    labels: Any
    format: Literal["raw", "png"]


class CameraReply(Reply, kw_only=True):
    name: str
    camera: dict[str, Any]


class CamerasReply(Reply, kw_only=True):
    cameras: list[dict[str, Any]]


class RaycastReply(Reply, kw_only=True):
    hits: Annotated[bytes, msgspec.Meta(description="one byte per ray: 1 hit, 0 missed")]
    entities: list[str]  # "" for a miss
    points: Vectors
    normals: Vectors
    distances: Numbers


class ContactsReply(Reply, kw_only=True):
    count: int
    a: list[str]
    b: list[str]
    positions: Vectors
    normals: Vectors
    forces: Numbers
    penetrations: Numbers


class TakeControlReply(Reply, kw_only=True):
    controller: str
    taken: bool


class ReleaseControlReply(Reply, kw_only=True):
    controller: None
    released: bool


class StreamReply(Reply, kw_only=True):
    stream: str
    key: str
    topic: str
    rate: float
    world: str
    # Over ZeroMQ: the stream ends when its connection sends nothing for this long (any
    # request keeps it; the SDK sends status); None over Zenoh (the liveliness token).
    silence_s: float | None = None


class StreamClosedReply(Reply, kw_only=True):
    stream: str
    closed: bool


def decode_result(declared: type[R], result: dict[str, Any], *, exact: bool = False) -> R:
    """A reply's result map as its declared type; one that does not fit is a daemon that
    speaks another protocol (MalformedRequestError on the client's side). ``exact``: a field
    the declaration lacks, at any depth, does not fit either."""
    try:
        decoded = msgspec.convert(result, declared)
    except msgspec.ValidationError as exc:
        raise MalformedRequestError(f"the daemon's reply does not fit its declaration: "
                                    f"{exc}") from None
    extra = _undeclared(decoded, result, "$") if exact else []
    if extra:
        raise MalformedRequestError(f"the daemon's reply does not fit its declaration: "
                                    f"{', '.join(extra)} not declared in {declared.__name__}")
    return decoded


def _undeclared(decoded: Any, raw: Any, path: str) -> list[str]:
    """The paths of the fields in ``raw`` that ``decoded`` (its Struct) does not declare."""
    if isinstance(decoded, list):
        return [p for i, (d, r) in enumerate(zip(decoded, raw, strict=True))
                for p in _undeclared(d, r, f"{path}[{i}]")]
    if not isinstance(decoded, msgspec.Struct):
        return []
    known = decoded.__struct_fields__
    return [f"{path}.{key}" for key in raw if key not in known] + [
        p for key in known if key in raw
        for p in _undeclared(getattr(decoded, key), raw[key], f"{path}.{key}")]
