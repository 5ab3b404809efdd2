"""Every operation's request, declared once as a msgspec Struct: its fields, their types,
ranges, choices and defaults.

protocol/operations.py reads its argument table (names, kinds, what is required) from these
classes; the daemon converts a request's ``args`` map into its class before any handler runs
(``decode_args``), so a handler receives a typed object; ``galton-client schema`` prints
their JSON Schema. Each field's wire kind (docs/protocol.md) rides in its type's metadata,
so that the fuzzer and the CLI keep reading kinds. A field that is ``None`` was not sent.

Type and range errors become INVALID_ARGUMENT with the "op.field" path and the offending
value; the deeper checks (finite rows, unit quaternions, names known to the world) stay
with the handlers, which run after this.
"""

from __future__ import annotations

from types import UnionType
from typing import Annotated, Any, Literal, TypeVar, Union, get_args, get_origin

import msgspec

from galton.protocol.errors import (
    InvalidArgumentError,
    MalformedRequestError,
    brief,
    did_you_mean,
)
from galton.protocol.vocabulary import (
    MODEL_FORMATS,
    EngineName,
    EntityKind,
    ImageFormat,
    ResetScope,
    TargetMode,
    check_fields,
)

R = TypeVar("R", bound="Reply")
A = TypeVar("A", bound="Args")


def _kind(kind: str, **extra: Any) -> msgspec.Meta:
    return msgspec.Meta(extra={"kind": kind, **extra})


Number = Annotated[float, _kind("number")]
Count = Annotated[int, _kind("count")]
Text = Annotated[str, _kind("string")]
LongText = Annotated[str, _kind("string", long_text=True)]
Flag = Annotated[bool, _kind("bool")]
Names = Annotated[list[str], _kind("names")]
Fields = Annotated[dict[str, Any], _kind("map")]
Groups = Annotated[list[dict[str, Any]], _kind("groups")]
Cameras = Annotated[list[dict[str, Any]], _kind("cameras")]
Poses = Annotated[bytes, _kind("poses", description="packed float64 rows, 7 wide")]
Twists = Annotated[bytes, _kind("twists", description="packed float64 rows, 6 wide")]
Wrenches = Annotated[bytes, _kind("wrenches", description="packed float64 rows, 6 wide")]
Points = Annotated[bytes, _kind("points", description="packed float64 rows, 3 wide")]
Blob = Annotated[bytes, _kind("blob", long_text=True)]
Values = Annotated[float | bytes, _kind("values")]
# A load_model format the engine does not load is FEATURE_UNSUPPORTED, not a bad argument:
# its choices are advertised, the handler checks them against the engine.
Format = Annotated[str, _kind("choice", choices=MODEL_FORMATS)]
Scope = Annotated[ResetScope, _kind("choice")]
Engine = Annotated[EngineName, _kind("choice")]
Mode = Annotated[TargetMode, _kind("choice")]
Kind = Annotated[EntityKind, _kind("choice")]
Image = Annotated[ImageFormat, _kind("choice")]


class Args(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """What every request may carry: the world it is for (the live one when None). Any
    value is taken here: a world that is not a known name, a string or not, is NOT_FOUND."""

    world: Annotated[Any, msgspec.Meta(extra_json_schema={"type": ["string", "null"]})] = None


class NoArgs(Args, kw_only=True, forbid_unknown_fields=True):
    """An operation that takes nothing but ``world``."""


class Play(Args, kw_only=True, forbid_unknown_fields=True):
    rtf: Number | None = None


class SetRtf(Args, kw_only=True, forbid_unknown_fields=True):
    rtf: Number


class Step(Args, kw_only=True, forbid_unknown_fields=True):
    count: Count | None = None
    read: Names | None = None
    read_joints: Names | None = None


class RunUntil(Args, kw_only=True, forbid_unknown_fields=True):
    sim_time: Number
    read: Names | None = None
    until_rest: Fields | None = None
    read_joints: Names | None = None


class Reset(Args, kw_only=True, forbid_unknown_fields=True):
    scope: Scope | None = None


class LoadWorld(Args, kw_only=True, forbid_unknown_fields=True):
    engine: Engine
    params: Fields | None = None


class Spawn(Args, kw_only=True, forbid_unknown_fields=True):
    groups: Groups


class LoadModel(Args, kw_only=True, forbid_unknown_fields=True):
    format: Format
    text: LongText | None = None
    path: Text | None = None
    prefix: Text | None = None
    fixed_base: Flag | None = None
    search_path: Text | None = None


class List(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text | None = None
    tag: Text | None = None
    kind: Kind | None = None


class NamesOrAll(Args, kw_only=True, forbid_unknown_fields=True):
    """Entities (or joints) by name; None: all of them."""

    names: Names | None = None


class NamedOnly(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names


class SetStates(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    poses: Poses | None = None
    twists: Twists | None = None


class Update(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    properties: Fields


class Joints(Args, kw_only=True, forbid_unknown_fields=True):
    model: Text | None = None
    names: Names | None = None


class SetJointStates(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    positions: Values
    velocities: Values | None = None
    read: Names | None = None


class SetJointTargets(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    mode: Mode
    targets: Values | None = None
    kp: Values | None = None
    kd: Values | None = None
    max_effort: Values | None = None


class ApplyWrench(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    wrenches: Wrenches
    points: Points | None = None
    duration: Number | None = None


class Snapshot(Args, kw_only=True, forbid_unknown_fields=True):
    slot: Text | None = None
    blob: Flag | None = None


class Restore(Args, kw_only=True, forbid_unknown_fields=True):
    slot: Text | None = None
    blob: Blob | None = None


class Slot(Args, kw_only=True, forbid_unknown_fields=True):
    slot: Text


class CreateWorld(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text
    engine: Engine | None = None
    params: Fields | None = None


class ForkWorld(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text
    source: Text | None = None


class Named(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text


class Predict(Args, kw_only=True, forbid_unknown_fields=True):
    horizon: Number
    every: Number | None = None
    read: Names | None = None
    read_joints: Names | None = None
    slot: Text | None = None
    set_states: Fields | None = None
    joint_targets: Fields | None = None
    wrenches: Fields | None = None


class Compare(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    poses: Poses
    twists: Twists | None = None
    sigma_position: Number | None = None
    sigma_angle: Number | None = None
    sigma_speed: Number | None = None
    correct: Flag | None = None


class Render(Args, kw_only=True, forbid_unknown_fields=True):
    cameras: Cameras
    format: Image | None = None


class AddCamera(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text
    camera: Fields


class Raycast(Args, kw_only=True, forbid_unknown_fields=True):
    origins: Points
    directions: Points | None = None
    ends: Points | None = None
    max_length: Number | None = None


class SetParams(Args, kw_only=True, forbid_unknown_fields=True):
    params: Fields


class StreamStates(Args, kw_only=True, forbid_unknown_fields=True):
    rate: Number | None = None
    names: Names | None = None


class CloseStream(Args, kw_only=True, forbid_unknown_fields=True):
    stream: Text


# -- replies: what a result map holds (declared for the operations converted so far) ------


class Reply(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """A reply's ``result`` map."""


class StatesReply(Reply, kw_only=True, forbid_unknown_fields=True):
    names: list[str]
    poses: Poses
    twists: Twists


class BoundsReply(Reply, kw_only=True, forbid_unknown_fields=True):
    names: list[str]
    bounds: Annotated[bytes, _kind("bounds", description="packed float64 rows, 6 wide: "
                                                         "min x y z, max x y z")]


class ShapesReply(Reply, kw_only=True, forbid_unknown_fields=True):
    """Each entity's collision shapes, flat: ``counts[i]`` rows belong to ``names[i]``."""

    names: list[str]
    counts: list[int]
    kinds: list[str]
    sizes: Annotated[bytes, _kind("sizes", description="packed float64 rows, 3 wide: half "
                                                       "sizes as SIZE_LAYOUT, zero padded")]
    poses: Annotated[bytes, _kind("poses", description="packed float64 rows, 7 wide: each "
                                                       "shape's pose in its entity's frame")]
    # Sent only when some row is a ``mesh`` (a reply without one is as before meshes were
    # told): per row, its index into ``mesh_vertices`` / ``mesh_faces``, -1 for a primitive
    # or for a mesh the daemon knows only as its box. Rows of one mesh share one index.
    meshes: list[int] = msgspec.field(default_factory=list)
    mesh_vertices: list[Annotated[bytes, _kind("points", description="packed float64 rows, "
                                                "3 wide: in its row's frame")]] = \
        msgspec.field(default_factory=list)
    mesh_faces: list[Annotated[bytes, _kind("faces", description="packed uint32 rows, 3 "
                                             "wide: vertex indices")]] = \
        msgspec.field(default_factory=list)


class StatusReply(Reply, kw_only=True, forbid_unknown_fields=True):
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


class CountReply(Reply, kw_only=True, forbid_unknown_fields=True):
    count: int


class NamesReply(Reply, kw_only=True, forbid_unknown_fields=True):
    names: list[str]


class ParamsReply(Reply, kw_only=True, forbid_unknown_fields=True):
    params: dict[str, Any]


class EntitiesReply(Reply, kw_only=True, forbid_unknown_fields=True):
    entities: list[dict[str, Any]]


def decode_result(declared: type[R], result: dict[str, Any]) -> R:
    """A reply's result map as its declared type; one that does not fit is a daemon that
    speaks another protocol (MalformedRequestError on the client's side)."""
    try:
        return msgspec.convert(result, declared)
    except msgspec.ValidationError as exc:
        raise MalformedRequestError(f"the daemon's reply does not fit its declaration: "
                                    f"{exc}") from None


def decode_args(op: str, declared: type[A], args: dict[str, Any]) -> A:
    """``args`` as the operation's typed request. A field it does not declare is refused
    naming the closest one; a value of the wrong type or out of range is INVALID_ARGUMENT
    naming "op.field" and quoting the value."""
    named = [f for f in declared.__struct_fields__ if f != "world"]
    check_fields(args, (*named, "world"), op)
    try:
        return msgspec.convert(args, declared)
    except msgspec.ValidationError as exc:
        raise InvalidArgumentError(explain(op, declared, str(exc), args)) from None


def explain(op: str, declared: type[Args], error: str, args: dict[str, Any]) -> str:
    """msgspec's ``Expected `int`, got `str` - at `$.count``` as the daemon's own message:
    ``step.count must be int, got 'ten'`` (did you mean, for a choice)."""
    what, _, path = error.partition(" - at `")
    steps = _path_steps(path.rstrip("`"))
    where = op + "".join(f"[{s}]" if isinstance(s, int) else f".{s}" for s in steps)
    if what.startswith("Object missing required field"):
        field = what.rsplit("`", 2)[-2]
        return f"{where}: missing required field {field!r}"
    value = _value_at(args, steps)
    if what.startswith("Invalid enum value"):
        choices = field_kind(declared, str(steps[0]))[1] if steps else ()
        return (f"{where} {brief(value)} is not one of {', '.join(choices)}"
                f"{did_you_mean(str(value)[:64], choices)}")
    if what.startswith("Expected `"):  # "Expected `int | null`, got `str`"
        expected = what.split("`")[1].removesuffix(" | null")  # None means "not sent"
        return f"{where} must be {expected}, got {brief(value)}"
    return f"{where}: {what[:1].lower()}{what[1:]}, got {brief(value)}"  # ranges, lengths


def _path_steps(path: str) -> list[str | int]:
    steps: list[str | int] = []
    for part in path.removeprefix("$").replace("[", ".[").split("."):
        if part.startswith("["):
            steps.append(int(part.strip("[]")))
        elif part:
            steps.append(part)
    return steps


def _value_at(args: Any, steps: list[str | int]) -> Any:
    value = args
    for step in steps:
        try:
            value = value[step]
        except (KeyError, IndexError, TypeError):
            return None
    return value


def field_kind(declared: type[Args], name: str) -> tuple[str, tuple[str, ...], bool]:
    """A field's wire kind, its choices and whether it may exceed the string limit, read
    from its declared type."""
    field = next(f for f in msgspec.structs.fields(declared) if f.name == name)
    tp = field.type
    if get_origin(tp) in (Union, UnionType):  # X | None
        tp = next(a for a in get_args(tp) if a is not type(None))
    base, *metas = get_args(tp)
    extra: dict[str, Any] = {}
    for meta in metas:
        extra.update(meta.extra or {})
    choices = get_args(base) if get_origin(base) is Literal else extra.get("choices", ())
    return str(extra["kind"]), tuple(choices), bool(extra.get("long_text", False))
