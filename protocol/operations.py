"""Every operation of the protocol, declared once: its request and reply types (shared ones
in protocol/requests.py and protocol/replies.py; a newer operation's beside its entry here,
in one block), and what it does to a world.

The daemon refuses an argument not declared here (INVALID_ARGUMENT, with a "did you mean"),
the fuzz harness generates requests from these declarations, and docs/protocol.md is held
to them by a test. Each argument's ``kind`` names the value it takes on the wire:

- ``number``: a finite int or float; ``count``: an int; ``string``; ``bool``;
- ``names``: a list of entity names; ``map``: a msgpack map (its fields checked by the op);
- ``groups``: a list of body-group maps (docs/protocol.md, "spawn");
- ``poses`` / ``twists``: msgpack bin of packed float64 rows (7 and 6 wide);
- ``choice``: a string, one of ``choices``;
- ``values``: one number per named joint, as a number (the same for all) or msgpack bin of
  packed float64; ``wrenches`` / ``points``: bin of packed float64 rows, 6 and 3 wide;
- ``blob``: msgpack bin (a snapshot's bytes); ``cameras``: a list of camera maps
  (docs/protocol.md, "render").
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Annotated, Any

import msgspec

from galton.protocol import replies as rp
from galton.protocol import requests as rq
from galton.protocol.errors import UnknownOperationError, did_you_mean
from galton.protocol.vocabulary import check_fields

ARG_KINDS = ("number", "count", "string", "bool", "names", "map", "groups", "poses", "twists",
             "choice", "values", "wrenches", "points", "blob", "cameras", "plans")
# Every request may name the world it is for (one world per daemon for now).
WORLD_ARG = "world"


@dataclass(frozen=True)
class Arg:
    """One argument of an operation."""

    name: str
    kind: str
    required: bool = False
    choices: tuple[str, ...] = ()
    long_text: bool = False  # may exceed the daemon's string limit (a model's text)

    def __post_init__(self) -> None:
        if self.kind not in ARG_KINDS:
            raise ValueError(f"argument {self.name}: unknown kind {self.kind!r}")


def args_of(declared: type[rq.Args]) -> tuple[Arg, ...]:
    """The argument table of a declared request (every field but ``world``)."""
    found = []
    for spec in msgspec.structs.fields(declared):
        if spec.name == WORLD_ARG:
            continue
        kind, choices, long_text = rq.field_kind(declared, spec.name)
        found.append(Arg(spec.name, kind, required=spec.required, choices=choices,
                         long_text=long_text))
    return tuple(found)


# A client's timeout for a long-running operation (one that steps the world) by default.
LONG_RUNNING_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class Operation:
    """One operation: its arguments, what it does to a world and how long a client waits.

    ``fast``: answered on the transport's thread from the last published state, without
    waiting for the physics thread. ``steps``: long-running, answered only when its steps
    are done (it belongs to its client, who may wait ``LONG_RUNNING_TIMEOUT_S``).
    ``timeout_floor_s``: the least a client should wait for it (rebuilding a world takes
    seconds), whatever its default timeout. ``viewer``: a client of the ``viewer`` role may
    ask it under ``--users`` (it changes no world: discovery, ``galton-client view``);
    every front's access rules follow this field (daemon/access/roles.py).
    """

    name: str
    request: type[rq.Args] = rq.NoArgs
    mutates: bool = False
    steps: bool = False
    fast: bool = False
    timeout_floor_s: float = 0.0
    viewer: bool = False
    reply: type[rp.Reply] | None = None  # its result map (protocol/replies.py); every op has one
    args: tuple[Arg, ...] = field(init=False, default=())

    def __post_init__(self) -> None:
        object.__setattr__(self, "args", args_of(self.request))
        if self.viewer and self.mutates:
            raise ValueError(f"operation {self.name}: a viewer may not ask one that mutates")

    def decode(self, args: dict[str, Any]) -> rq.Args:
        """The request's args as its declared type (INVALID_ARGUMENT when they do not fit);
        names it does not declare are refused first, with a "did you mean"."""
        return rq.decode_args(self.name, self.request, args)

    def arg(self, name: str) -> Arg | None:
        return next((a for a in self.args if a.name == name), None)

    @property
    def arg_names(self) -> tuple[str, ...]:
        return tuple(a.name for a in self.args)

    def check_arg_names(self, args: dict[str, Any]) -> None:
        """Refuse any argument this operation does not declare, naming the closest one."""
        check_fields(args, (*self.arg_names, WORLD_ARG), self.name)

    def client_timeout(self, default_s: float) -> float:
        """How long a client waits for this operation when the caller names no timeout."""
        if self.steps:
            return LONG_RUNNING_TIMEOUT_S
        return max(default_s, self.timeout_floor_s)


# -- operations declared whole here: request type, reply type and entry side by side. A new
# operation is one such block (docs/ARCHITECTURE.md, "How to add an operation"); the shared
# types it may reuse sit in protocol/requests.py and protocol/replies.py.


class GetEntities(rq.Args, kw_only=True, forbid_unknown_fields=True):
    """get_entities' filters, as ROS 2 simulation_interfaces' GetEntities: a glob (as
    ``list``'s) matched against each name, and a box (two points: min corner, max corner)
    each entity's bounds must touch. An entity passes every filter sent; none: every one."""

    pattern: rq.Text | None = None
    region: rq.Points | None = None


GET_ENTITIES = Operation("get_entities", GetEntities, reply=rp.NamesReply)


# calibrate's field types (declared with it, below GET_ENTITIES).
CalibrationTimes = Annotated[bytes, msgspec.Meta(extra={
    "kind": "values", "description": "packed float64, one sample time (s) per sample"})]
Bounds = rq.FitBound
FitBounds = rq.FitBounds  # shared with compare's trigger (its ``calibrate``)
MaxPredictions = rq.MaxPredictions
Population = rq.Population
Seed = rq.FitSeed


class Calibrate(rq.Args, kw_only=True, forbid_unknown_fields=True):
    """calibrate: fit body and world parameters so that a prediction from ``times[0]``
    matches what was observed (docs/protocol.md, "calibrate"). ``fit`` maps each parameter
    ("box.friction", "ball*.restitution", "box.mass", "gravity") to its [low, high];
    ``poses`` holds ``len(times)`` samples of ``names`` (a NaN row: not seen then)."""

    names: rq.Names
    times: CalibrationTimes
    poses: rq.Poses
    fit: FitBounds
    slot: rq.Text | None = None  # start from this snapshot; None: the world, set to sample 0
    twists: rq.Twists | None = None  # sample 0's twists; None: from its first samples
    apply: rq.Flag = False
    max_predictions: MaxPredictions = 200
    population: Population | None = None  # None: 4 + 3 ln(parameters), at least 6
    seed: Seed = 0


class CalibrateReply(rp.Reply, kw_only=True):
    fitted: dict[str, float]
    intervals: dict[str, list[float]]
    error_before: float
    error_after: float
    predictions: int
    generations: int
    steps: int
    converged: bool
    applied: bool
    batches: int  # batches of futures the predictions ran in (a generation each)


# It mutates as compare does: with ``apply`` it sets the fitted values (the lease applies).
CALIBRATE = Operation("calibrate", Calibrate, mutates=True, steps=True, reply=CalibrateReply)


_REBUILDS = 30.0  # operations that may rebuild the engine's world wait at least this long
OPERATIONS: dict[str, Operation] = {op.name: op for op in (
    Operation("status", rq.NoArgs, fast=True, viewer=True, reply=rp.StatusReply),
    Operation("capabilities", rq.NoArgs, viewer=True, reply=rp.CapabilitiesReply),
    Operation("play", rq.Play, mutates=True, reply=rp.StatusReply),
    Operation("set_rtf", rq.SetRtf, mutates=True, reply=rp.StatusReply),
    Operation("pause", rq.NoArgs, mutates=True, reply=rp.StatusReply),
    Operation("stop", rq.NoArgs, mutates=True, reply=rp.StatusReply),
    Operation("step", rq.Step, mutates=True, steps=True, reply=rp.StepReply),
    Operation("run_until", rq.RunUntil, mutates=True, steps=True,
              reply=rp.StepReply),
    Operation("reset", rq.Reset, mutates=True, reply=rp.StatusReply),
    Operation("load_world", rq.LoadWorld, mutates=True, timeout_floor_s=_REBUILDS,
              reply=rp.StatusReply),
    Operation("spawn", rq.Spawn, mutates=True, timeout_floor_s=_REBUILDS, reply=rp.NamesReply),
    Operation("load_model", rq.LoadModel, mutates=True, timeout_floor_s=_REBUILDS,
              reply=rp.NamesReply),
    Operation("list", rq.List, viewer=True, reply=rp.EntitiesReply),
    Operation("get_states", rq.NamesOrAll, reply=rp.StatesReply),
    Operation("get_bounds", rq.NamesOrAll, reply=rp.BoundsReply),
    Operation("get_shapes", rq.NamesOrAll, viewer=True, reply=rp.ShapesReply),
    GET_ENTITIES,
    Operation("set_states", rq.SetStates, mutates=True, reply=rp.CountReply),
    Operation("update", rq.Update, mutates=True, reply=rp.CountReply),
    Operation("delete", rq.NamedOnly, mutates=True, timeout_floor_s=_REBUILDS, reply=rp.CountReply),
    Operation("joints", rq.Joints, reply=rp.JointsReply),
    Operation("get_joint_states", rq.NamesOrAll, reply=rp.JointStatesReply),
    Operation("set_joint_states", rq.SetJointStates, mutates=True,
              reply=rp.SetJointStatesReply),
    Operation("set_joint_targets", rq.SetJointTargets, mutates=True, reply=rp.CountReply),
    Operation("apply_wrench", rq.ApplyWrench, mutates=True, reply=rp.CountReply),
    Operation("clear_wrenches", rq.NamesOrAll, mutates=True, reply=rp.CountReply),
    Operation("snapshot", rq.Snapshot, reply=rp.SnapshotReply),
    Operation("restore", rq.Restore, mutates=True, timeout_floor_s=_REBUILDS,
              reply=rp.WorldReply),
    Operation("snapshots", rq.NoArgs, reply=rp.SnapshotsReply),
    Operation("delete_snapshot", rq.Slot, reply=rp.CountReply),
    Operation("list_worlds", rq.NoArgs, viewer=True, reply=rp.WorldsReply),
    Operation("create_world", rq.CreateWorld, timeout_floor_s=_REBUILDS,
              reply=rp.WorldReply),
    Operation("fork_world", rq.ForkWorld, timeout_floor_s=_REBUILDS, reply=rp.WorldReply),
    Operation("delete_world", rq.Named, reply=rp.CountReply),
    Operation("predict", rq.Predict, steps=True, reply=rp.PredictReply),
    Operation("compare", rq.Compare, mutates=True, reply=rp.CompareReply),
    Operation("render", rq.Render, reply=rp.RenderReply),
    Operation("add_camera", rq.AddCamera, mutates=True, reply=rp.CameraReply),
    Operation("remove_camera", rq.Named, mutates=True, reply=rp.CountReply),
    Operation("cameras", rq.NoArgs, reply=rp.CamerasReply),
    Operation("raycast", rq.Raycast, reply=rp.RaycastReply),
    Operation("contacts", rq.NamesOrAll, viewer=True, reply=rp.ContactsReply),
    Operation("get_params", rq.NoArgs, reply=rp.ParamsReply),
    Operation("set_params", rq.SetParams, mutates=True, reply=rp.ParamsReply),
    # The control lease (daemon/access/lease.py): they change who may mutate, not the world.
    Operation("take_control", rq.NoArgs, reply=rp.TakeControlReply),
    Operation("release_control", rq.NoArgs, reply=rp.ReleaseControlReply),
    # State streams (daemon/world/state_streams.py): poses published at a client's rate.
    Operation("stream_states", rq.StreamStates, viewer=True, reply=rp.StreamReply),
    Operation("close_stream", rq.CloseStream, viewer=True, reply=rp.StreamClosedReply),
    CALIBRATE,
)}


def json_schema() -> dict[str, Any]:
    """Every operation's request (its ``args`` map) and declared reply (its ``result``
    map) as JSON Schema (2020-12), for clients in other languages: msgpack bins appear as
    base64 strings, as a JSON rendering of the wire would carry them."""
    types = [t for op in OPERATIONS.values() for t in (op.request, op.reply) if t is not None]
    refs, defs = msgspec.json.schema_components(types, ref_template="#/$defs/{name}")
    defs = _without_finite_sentinels(defs)
    by_type = dict(zip(types, refs, strict=True))
    operations = {name: {"request": by_type[op.request],
                         "reply": by_type[op.reply] if op.reply is not None else {}}
                  for name, op in OPERATIONS.items()}
    return {"$schema": "https://json-schema.org/draft/2020-12/schema", "$defs": defs,
            "operations": operations}


def _without_finite_sentinels(node: Any) -> Any:
    """``node`` less the +-1.8e308 bounds that make a number finite: the daemon checks
    them, JSON cannot carry NaN or infinity, and to a reader they are noise."""
    if isinstance(node, list):
        return [_without_finite_sentinels(item) for item in node]
    if not isinstance(node, dict):
        return node
    return {key: _without_finite_sentinels(value) for key, value in node.items()
            if not (key in _BOUND_KEYS and abs(value) == rq.FINITE_BOUND)}


_BOUND_KEYS = frozenset({"minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum"})


def operation(name: str) -> Operation:
    """The operation of that name, or UnknownOperationError with the closest names."""
    found = OPERATIONS.get(name)
    if found is None:
        known = sorted(OPERATIONS)
        raise UnknownOperationError(
            f"unknown operation {name[:64]!r}{did_you_mean(name[:64], known)}",
            {"operations": known})
    return found
