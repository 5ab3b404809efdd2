"""Every operation's request, declared once as a msgspec Struct: its fields, their types,
ranges, choices and defaults.

protocol/operations.py reads its argument table (names, kinds, what is required) from these
classes; the daemon converts a request's ``args`` map into its class before any handler runs
(``decode_args``), so a handler receives a typed object; ``galton-client schema`` prints
their JSON Schema. Each field's wire kind (docs/protocol.md) rides in its type's metadata,
so that the fuzzer and the CLI keep reading kinds. A field that is ``None`` was not sent.

A field's range rides in its type too (``msgspec.Meta``: every number is finite, a rate
in [1, 60] Hz, a horizon > 0), and so does its default; a field sent as nil is as if it
was not sent. Type and range errors become INVALID_ARGUMENT with the "op.field" path, the
range and the offending value; the deeper checks (finite rows, unit quaternions, names
known to the world, the daemon's configurable limits) stay with the handlers, which run
after this.
"""

from __future__ import annotations

import math
import sys
from types import UnionType
from typing import Annotated, Any, Literal, TypeVar, Union, get_args, get_origin

import msgspec

from galton.protocol.errors import InvalidArgumentError, brief, did_you_mean
from galton.protocol.vocabulary import (
    DEFAULT_MAX_LENGTH,
    DEFAULT_RATE_HZ,
    DEFAULT_SIGMA_ANGLE,
    DEFAULT_SIGMA_POSITION,
    DEFAULT_SIGMA_SPEED,
    MAX_BATCH,
    MAX_CAMERA_NAME,
    MAX_CAMERAS_PER_REQUEST,
    MAX_COORDINATE,
    MAX_EFFORT,
    MAX_FORCE,
    MAX_FRICTION,
    MAX_GAIN,
    MAX_JOINT_POSITION,
    MAX_JOINT_SPEED,
    MAX_MASS,
    MAX_RATE_HZ,
    MAX_RTF,
    MAX_TORQUE,
    MAX_TWIST,
    MAX_WORLD_NAME,
    MIN_MASS,
    MIN_RATE_HZ,
    MODEL_FORMATS,
    QUATERNION_NORM_BAND,
    EngineName,
    EntityKind,
    ImageFormat,
    ResetScope,
    TargetMode,
    check_fields,
)

A = TypeVar("A", bound="Args")


def _kind(kind: str, **extra: Any) -> msgspec.Meta:
    return msgspec.Meta(extra={"kind": kind, **extra})


# Every number is finite: NaN and the infinities fail these bounds (msgspec checks them in C).
# The exported JSON Schema leaves them out (operations.json_schema): they are no real range.
_BIG = FINITE_BOUND = sys.float_info.max
Number = Annotated[float, _kind("number"), msgspec.Meta(ge=-_BIG, le=_BIG)]
Positive = Annotated[float, _kind("number"), msgspec.Meta(gt=0.0, le=_BIG)]
NonNegative = Annotated[float, _kind("number"), msgspec.Meta(ge=0.0, le=_BIG)]
Rtf = Annotated[float, _kind("number"), msgspec.Meta(ge=0.0, le=MAX_RTF)]
RateHz = Annotated[float, _kind("number"), msgspec.Meta(ge=MIN_RATE_HZ, le=MAX_RATE_HZ)]
Count = Annotated[int, _kind("count"), msgspec.Meta(ge=1)]
Text = Annotated[str, _kind("string")]
LongText = Annotated[str, _kind("string", long_text=True)]
# The name of a world or slot being made, of a camera being added (that each is printable
# is the handler's check: msgspec cannot declare str.isprintable).
NewName = Annotated[str, _kind("string"), msgspec.Meta(min_length=1, max_length=MAX_WORLD_NAME)]
CameraName = Annotated[str, _kind("string"),
                       msgspec.Meta(min_length=1, max_length=MAX_CAMERA_NAME)]
Flag = Annotated[bool, _kind("bool")]
# A names list holds 1 to MAX_BATCH names; each name's form (printable, distinct) is checked
# by the handler (protocol/model.check_names), which msgspec cannot declare.
Names = Annotated[list[str], _kind("names"), msgspec.Meta(min_length=1, max_length=MAX_BATCH)]
# stream_states: empty means every entity.
NamesOrEvery = Annotated[list[str], _kind("names")]
Fields = Annotated[dict[str, Any], _kind("map")]
Groups = Annotated[list[dict[str, Any]], _kind("groups")]
Cameras = Annotated[list[dict[str, Any]], _kind("cameras"),
                    msgspec.Meta(min_length=1, max_length=MAX_CAMERAS_PER_REQUEST)]
# Packed rows and per-joint values carry their bounds (docs/protocol.md, "Bounds"): msgspec
# cannot range-check the numbers inside bytes, so protocol/model.py's decoders check them,
# before any engine sees them, against these same constants (``value_bound`` reads them).
Poses = Annotated[bytes, _kind("poses", description="packed float64 rows, 7 wide",
                               bound=MAX_COORDINATE, quaternion_norm=QUATERNION_NORM_BAND)]
Twists = Annotated[bytes, _kind("twists", description="packed float64 rows, 6 wide",
                                bound=MAX_TWIST)]
Wrenches = Annotated[bytes, _kind("wrenches", description="packed float64 rows, 6 wide",
                                  bound=(MAX_FORCE, MAX_TORQUE))]
Points = Annotated[bytes, _kind("points", description="packed float64 rows, 3 wide",
                                bound=MAX_COORDINATE)]
Blob = Annotated[bytes, _kind("blob", long_text=True)]
# A spread of positions (compare.spread): m, as far as a coordinate may go.
Spreads = Annotated[float | bytes, _kind("values", bound=MAX_COORDINATE)]
JointPositions = Annotated[float | bytes, _kind("values", bound=MAX_JOINT_POSITION)]
JointSpeeds = Annotated[float | bytes, _kind("values", bound=MAX_JOINT_SPEED)]
# A target's bound is its mode's quantity: an angle or length, a speed, an effort.
Targets = Annotated[float | bytes, _kind("values", bound={
    "none": MAX_JOINT_POSITION, "position": MAX_JOINT_POSITION,
    "velocity": MAX_JOINT_SPEED, "effort": MAX_EFFORT})]
Gains = Annotated[float | bytes, _kind("values", bound=MAX_GAIN)]
Efforts = Annotated[float | bytes, _kind("values", bound=MAX_EFFORT)]
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
    rtf: Rtf | None = None  # None: the target it had


class SetRtf(Args, kw_only=True, forbid_unknown_fields=True):
    rtf: Rtf


class Step(Args, kw_only=True, forbid_unknown_fields=True):
    count: Count = 1  # at most the daemon's max_steps (its handler checks)
    read: Names | None = None
    read_joints: Names | None = None


class UntilRest(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """run_until's stop rule: once every read body moves slower than ``speed`` (m/s),
    looked at every ``every`` seconds of sim time."""

    speed: Positive
    every: Positive


class RunUntil(Args, kw_only=True, forbid_unknown_fields=True):
    sim_time: NonNegative
    read: Names | None = None
    until_rest: Annotated[UntilRest, _kind("map")] | None = None
    read_joints: Names | None = None


class Reset(Args, kw_only=True, forbid_unknown_fields=True):
    scope: Scope = "all"


class LoadWorld(Args, kw_only=True, forbid_unknown_fields=True):
    engine: Engine
    params: Fields | None = None


class Spawn(Args, kw_only=True, forbid_unknown_fields=True):
    groups: Groups


class LoadModel(Args, kw_only=True, forbid_unknown_fields=True):
    format: Format
    text: LongText | None = None
    path: Text | None = None
    prefix: Text = ""
    fixed_base: Flag = True
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


Unit = Annotated[float, _kind("number"), msgspec.Meta(ge=0.0, le=1.0)]


class UpdateProperties(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """``update``'s properties; one not sent (or nil) is left as it is. Each tag's form
    (a printable entity-like name) is the handler's check."""

    mass: Annotated[float, _kind("number"), msgspec.Meta(ge=MIN_MASS, le=MAX_MASS)] | None = None
    friction: Annotated[float, _kind("number"), msgspec.Meta(ge=0.0, le=MAX_FRICTION)] | None = None
    restitution: Unit | None = None
    rgba: Annotated[list[Unit], _kind("numbers"),
                    msgspec.Meta(min_length=4, max_length=4)] | None = None
    tags: Annotated[list[str], _kind("names")] | None = None


class Update(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    properties: Annotated[UpdateProperties, _kind("map")]


class Joints(Args, kw_only=True, forbid_unknown_fields=True):
    model: Text | None = None
    names: Names | None = None


class SetJointStates(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    positions: JointPositions
    velocities: JointSpeeds | None = None
    read: Names | None = None


class SetJointTargets(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    mode: Mode
    targets: Targets | None = None
    kp: Gains | None = None
    kd: Gains | None = None
    max_effort: Efforts | None = None  # +inf: no cap


class ApplyWrench(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    wrenches: Wrenches
    points: Points | None = None
    duration: Positive | None = None  # None: until clear_wrenches


class Snapshot(Args, kw_only=True, forbid_unknown_fields=True):
    slot: NewName | None = None
    blob: Flag = False


class Restore(Args, kw_only=True, forbid_unknown_fields=True):
    slot: Text | None = None
    blob: Blob | None = None


class Slot(Args, kw_only=True, forbid_unknown_fields=True):
    slot: Text


class CreateWorld(Args, kw_only=True, forbid_unknown_fields=True):
    name: NewName
    engine: Engine | None = None
    params: Fields | None = None


class ForkWorld(Args, kw_only=True, forbid_unknown_fields=True):
    name: NewName
    source: Text | None = None


class Named(Args, kw_only=True, forbid_unknown_fields=True):
    name: Text


MAX_FUTURES = 64  # futures one predict runs
# The index of a prediction's first future in a larger ensemble (its noise is drawn after
# that of the futures before it, each skipped draw costing a few normals per noisy body).
MAX_FIRST_FUTURE = 65_536
MAX_PLAN_STEPS = 1000  # timed actions in one future's plan
MAX_SIGMA_POSITION = 10.0  # m
MAX_SIGMA_VELOCITY = 100.0  # m/s
FutureCount = Annotated[int, _kind("count"), msgspec.Meta(ge=1, le=MAX_FUTURES)]
Seed = Annotated[int, _kind("count"), msgspec.Meta(ge=0, le=2**63 - 1)]
FirstFuture = Annotated[int, _kind("count"), msgspec.Meta(ge=0, le=MAX_FIRST_FUTURE)]


class Sigmas(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """Standard deviations of the noise a future's start is given: position (m, each
    axis), orientation (rad, each axis of a small rotation), linear velocity (m/s)."""

    position: Annotated[float, _kind("number"),
                        msgspec.Meta(ge=0.0, le=MAX_SIGMA_POSITION)] = 0.0
    orientation: Annotated[float, _kind("number"), msgspec.Meta(ge=0.0, le=math.pi)] = 0.0
    velocity: Annotated[float, _kind("number"),
                        msgspec.Meta(ge=0.0, le=MAX_SIGMA_VELOCITY)] = 0.0


class Perturb(Sigmas, kw_only=True, forbid_unknown_fields=True):
    """``predict``'s perturbation: these sigmas for every moving spawned body, and
    ``bodies`` naming bodies (models' roots included) with sigmas of their own."""

    bodies: Annotated[dict[str, Sigmas], _kind("map")] | None = None


class PlanStep(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """One timed action of a plan: at ``at`` seconds from the prediction's start, these
    joint targets and/or wrenches (each as its own request's arguments)."""

    at: NonNegative
    joint_targets: Fields | None = None
    wrenches: Fields | None = None


Plans = Annotated[list[Annotated[list[PlanStep], msgspec.Meta(max_length=MAX_PLAN_STEPS)]],
                  _kind("plans"), msgspec.Meta(min_length=1, max_length=MAX_FUTURES)]


class Score(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """One number per future: the distance (m) of body ``body`` to point ``target`` at the
    horizon."""

    body: Text
    target: Annotated[list[Number], _kind("numbers"), msgspec.Meta(min_length=3,
                                                                   max_length=3)]


class Predict(Args, kw_only=True, forbid_unknown_fields=True):
    horizon: Positive
    every: Positive | None = None  # None: every step
    read: Names | None = None
    read_joints: Names | None = None
    slot: Text | None = None
    set_states: Fields | None = None
    joint_targets: Fields | None = None
    wrenches: Fields | None = None
    futures: FutureCount | None = None  # None: one per plan, or 1
    perturb: Annotated[Perturb, _kind("map")] | None = None
    seed: Seed | None = None  # None: a fresh one, sent back
    first_future: FirstFuture = 0  # these are futures first_future.. of seed's ensemble
    plans: Plans | None = None
    score: Annotated[Score, _kind("map")] | None = None


MAX_TRIGGER_WINDOW = 100_000  # comparisons
# calibrate's fit and search (protocol/operations.py's Calibrate; a trigger's calibrate).
FitBound = Annotated[list[Number], msgspec.Meta(min_length=2, max_length=2)]
FitBounds = Annotated[dict[str, FitBound], msgspec.Meta(min_length=1, max_length=16,
                                                        extra={"kind": "map"})]
MaxPredictions = Annotated[int, msgspec.Meta(ge=2, le=100_000, extra={"kind": "count"})]
Population = Annotated[int, msgspec.Meta(ge=2, le=1024, extra={"kind": "count"})]
FitSeed = Annotated[int, msgspec.Meta(ge=0, le=2**32 - 1, extra={"kind": "count"})]


class TriggerCalibration(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """What a trigger's calibration fits, as ``calibrate``'s own fields: the daemon starts
    it over the streak's observations when the streak reaches the window."""

    fit: FitBounds
    apply: Flag = False
    max_predictions: MaxPredictions = 200
    population: Population | None = None
    seed: FitSeed = 0


class Trigger(msgspec.Struct, kw_only=True, forbid_unknown_fields=True):
    """compare's surprise trigger: ``window`` comparisons of a world in a row scoring above
    ``threshold`` suggest a calibration (a ``calibration_suggested`` event); with
    ``calibrate``, the daemon starts that calibration itself."""

    threshold: Positive
    window: Annotated[int, _kind("count"), msgspec.Meta(ge=1, le=MAX_TRIGGER_WINDOW)]
    calibrate: Annotated[TriggerCalibration, _kind("map")] | None = None


class Compare(Args, kw_only=True, forbid_unknown_fields=True):
    names: Names
    poses: Poses
    twists: Twists | None = None
    sigma_position: Positive = DEFAULT_SIGMA_POSITION
    sigma_angle: Positive = DEFAULT_SIGMA_ANGLE
    sigma_speed: Positive = DEFAULT_SIGMA_SPEED
    correct: Flag = False
    spread: Spreads | None = None  # m per body (or one for all): a prediction's spread
    trigger: Annotated[Trigger, _kind("map")] | None = None  # counts toward a surprise streak


class Render(Args, kw_only=True, forbid_unknown_fields=True):
    cameras: Cameras
    format: Image = "raw"


class AddCamera(Args, kw_only=True, forbid_unknown_fields=True):
    name: CameraName
    camera: Fields


Directions = Annotated[bytes, _kind("points", description="packed float64 rows, 3 wide: "
                                    "directions, finite, of any length")]


class Raycast(Args, kw_only=True, forbid_unknown_fields=True):
    origins: Points
    directions: Directions | None = None
    ends: Points | None = None
    max_length: Positive = DEFAULT_MAX_LENGTH


class SetParams(Args, kw_only=True, forbid_unknown_fields=True):
    params: Fields


class StreamStates(Args, kw_only=True, forbid_unknown_fields=True):
    rate: RateHz = DEFAULT_RATE_HZ
    names: NamesOrEvery | None = None


class CloseStream(Args, kw_only=True, forbid_unknown_fields=True):
    stream: Text


def decode_args(op: str, declared: type[A], args: dict[str, Any]) -> A:
    """``args`` as the operation's typed request. A field it does not declare is refused
    naming the closest one; a value of the wrong type or out of range is INVALID_ARGUMENT
    naming "op.field" and quoting the value. A field sent as nil takes its default."""
    named = [f for f in declared.__struct_fields__ if f != "world"]
    check_fields(args, (*named, "world"), op)
    if None in args.values():
        args = {key: value for key, value in args.items() if value is not None}
    try:
        return msgspec.convert(args, declared)
    except msgspec.ValidationError as exc:
        raise InvalidArgumentError(explain(op, declared, str(exc), args)) from None


def encode_args(request: msgspec.Struct) -> dict[str, Any]:
    """A typed request as the ``args`` map the daemon decodes (``decode_args`` undone): every
    field but those left None, which are not sent (the daemon takes a missing field and a
    nil alike); a field declared as a Struct (``until_rest``, ``perturb``) as its map. The
    SDK sends its requests so (``Client._send``); values go as they are, bytes as bytes."""
    return {name: _wire(value) for name in request.__struct_fields__
            if (value := getattr(request, name)) is not None}


def _wire(value: Any) -> Any:
    if isinstance(value, msgspec.Struct):
        return encode_args(value)
    if isinstance(value, dict):
        return {key: _wire(item) for key, item in value.items()}
    if isinstance(value, list) and value and isinstance(value[0], msgspec.Struct | list):
        return [_wire(item) for item in value]  # plans: lists of PlanStep
    return value


def decode_field(op: str, declared: type[Args], name: str, value: Any) -> Any:
    """One field of a request as its declared type, refused as ``decode_args`` would refuse
    it in the whole request (INVALID_ARGUMENT naming "op.name...", its range and value): the
    SDK types a map its caller gives (predict's ``perturb``) so."""
    field_type = next(f.type for f in msgspec.structs.fields(declared) if f.name == name)
    try:
        return msgspec.convert(value, field_type)
    except msgspec.ValidationError as exc:
        what, at, path = str(exc).partition(" - at `$")
        error = f"{what} - at `${'.' + name}{path if at else '`'}"
        raise InvalidArgumentError(explain(op, declared, error, {name: value})) from None


def explain(op: str, declared: type[Args], error: str, args: dict[str, Any]) -> str:
    """msgspec's ``Expected `int`, got `str` - at `$.count``` as the daemon's own message:
    ``step.count must be int, got 'ten'`` (did you mean, for a choice)."""
    what, _, path = error.partition(" - at `")
    steps = _path_steps(path.rstrip("`"))
    where = op + "".join(f"[{s}]" if isinstance(s, int) or s == _MAP_KEY else f".{s}"
                         for s in steps)
    if what.startswith("Object missing required field"):
        field = what.rsplit("`", 2)[-2]
        return f"{where}: missing required field {field!r}"
    if what.startswith("Object contains unknown field"):  # in a declared map (until_rest)
        field, allowed = what.rsplit("`", 2)[-2], _fields_at(declared, steps)
        return (f"{where} takes no field {field!r}{did_you_mean(field[:64], allowed)}; it "
                f"takes: {', '.join(allowed)}")
    value = _value_at(args, steps)
    owner = _struct_at(declared, steps[:-1])
    if what.startswith("Invalid enum value"):
        choices = field_kind(owner, str(steps[-1]))[1] if steps and owner else ()
        return (f"{where}{_quoted(value)} is not one of {', '.join(choices)}"
                f"{did_you_mean(str(value)[:64], choices)}")
    if what.startswith("Expected `"):  # "Expected `int | null`, got `str`"
        expected = what.split("`")[1].removesuffix(" | null")  # None means "not sent"
        if ", got `" not in what and owner and isinstance(steps[-1], str):  # a range
            expected = range_text(owner, steps[-1])
        elif ", got `" not in what:  # a list item's range: "float <= 1.0"
            expected = what.removeprefix("Expected ").replace("`", "").replace(" | null", "")
        return f"{where} must be {expected}{_got(value)}"
    return f"{where}: {what[:1].lower()}{what[1:]}{_got(value)}"  # ranges, lengths


# msgspec's step into a map's value ("$.bodies[...].position"): which key, it does not say.
_MAP_KEY = "..."
_UNSEEN = object()  # the offending value, in a map of several entries: not known


def _got(value: Any) -> str:
    return "" if value is _UNSEEN else f", got {brief(value)}"


def _quoted(value: Any) -> str:
    return "" if value is _UNSEEN else f" {brief(value)}"


def _struct_at(declared: type[msgspec.Struct], steps: list[str | int]
               ) -> type[msgspec.Struct] | None:
    """The declared Struct a path leads to (through fields declared as Structs, and maps of
    them: perturb's ``bodies``), if any."""
    found: Any = declared
    for step in steps:
        if step == _MAP_KEY and get_origin(found) is dict:
            found = get_args(found)[1]
        elif _is_struct(found) and isinstance(step, str) and step in found.__struct_fields__:
            found = _metas(found, step)[0]
        else:
            return None
    return found if _is_struct(found) else None


def _is_struct(found: Any) -> bool:
    return isinstance(found, type) and issubclass(found, msgspec.Struct)


def _fields_at(declared: type[msgspec.Struct], steps: list[str | int]) -> tuple[str, ...]:
    found = _struct_at(declared, steps)
    return () if found is None else found.__struct_fields__


def range_text(declared: type[msgspec.Struct], name: str) -> str:
    """A field's declared range in words: "a finite number in [0, 1e+06]", "an integer
    >= 1", "a list of 1 to 16 items"."""
    meta = _constraints(declared, name)
    if "min_length" in meta or "max_length" in meta:
        shortest, longest = meta.get("min_length", 0), meta.get("max_length", math.inf)
        if _metas(declared, name)[0] is str:
            return f"a string of {shortest:g} to {longest:g} characters"
        return f"a list of {shortest:g} to {longest:g} items"
    what = "a finite number" if field_kind(declared, name)[0] == "number" else "an integer"
    low = [f"{sign} {meta[k]:g}" for k, sign in (("ge", ">="), ("gt", ">"))
           if meta.get(k, -_BIG) != -_BIG]  # the finite bounds of every number say nothing
    high = [f"{sign} {meta[k]:g}" for k, sign in (("le", "<="), ("lt", "<"))
            if meta.get(k, _BIG) != _BIG]
    if low and high:
        return (f"{what} in {'[' if 'ge' in meta else '('}{low[0].split()[1]}, "
                f"{high[0].split()[1]}{']' if 'le' in meta else ')'}")
    return " ".join([what, *low, *high])


def _constraints(declared: type[msgspec.Struct], name: str) -> dict[str, Any]:
    """The bounds (ge, gt, le, lt, min_length, max_length) a field's type declares."""
    found: dict[str, Any] = {}
    for meta in _metas(declared, name)[1]:
        for key in ("ge", "gt", "le", "lt", "min_length", "max_length"):
            if getattr(meta, key) is not None:
                found[key] = getattr(meta, key)
    return found


def _metas(declared: type[msgspec.Struct], name: str) -> tuple[Any, list[msgspec.Meta]]:
    """A field's base type and the msgspec.Meta annotations on it (through ``X | None``)."""
    field = next(f for f in msgspec.structs.fields(declared) if f.name == name)
    tp = field.type
    if get_origin(tp) in (Union, UnionType):  # X | None
        tp = next(a for a in get_args(tp) if a is not type(None))
    base, *metas = get_args(tp)
    return base, [m for m in metas if isinstance(m, msgspec.Meta)]


def _path_steps(path: str) -> list[str | int]:
    steps: list[str | int] = []
    marked = path.removeprefix("$").replace(f"[{_MAP_KEY}]", ".<key>")
    for part in marked.replace("[", ".[").split("."):
        if part == "<key>":
            steps.append(_MAP_KEY)
        elif part.startswith("["):
            steps.append(int(part.strip("[]")))
        elif part:
            steps.append(part)
    return steps


def _value_at(args: Any, steps: list[str | int]) -> Any:
    value = args
    for step in steps:
        if step == _MAP_KEY and isinstance(value, dict):  # which entry: known if only one
            value = next(iter(value.values())) if len(value) == 1 else _UNSEEN
            if value is _UNSEEN:
                return value
            continue
        try:
            value = value[step]
        except (KeyError, IndexError, TypeError):
            return None
    return value


def value_bound(declared: type[msgspec.Struct], name: str, mode: str | None = None) -> float:
    """The bound (+-) a packed or per-joint field's numbers must keep, as declared in its
    type; a target's depends on its ``mode``."""
    extra: dict[str, Any] = {}
    for meta in _metas(declared, name)[1]:
        extra.update(meta.extra or {})
    bound = extra["bound"]
    return float(bound[mode or "none"] if isinstance(bound, dict) else bound)


def field_kind(declared: type[msgspec.Struct], name: str) -> tuple[str, tuple[str, ...], bool]:
    """A field's wire kind, its choices and whether it may exceed the string limit, read
    from its declared type."""
    base, metas = _metas(declared, name)
    extra: dict[str, Any] = {}
    for meta in metas:
        extra.update(meta.extra or {})
    choices = get_args(base) if get_origin(base) is Literal else extra.get("choices", ())
    return str(extra["kind"]), tuple(choices), bool(extra.get("long_text", False))
