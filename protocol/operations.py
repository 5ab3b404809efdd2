"""Every operation of the protocol, declared once: its arguments, and what it does to a world.

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

from dataclasses import dataclass
from typing import Any

from galton.protocol.errors import UnknownOperationError, did_you_mean
from galton.protocol.vocabulary import ENGINE_NAMES, TARGET_MODES, check_fields

ARG_KINDS = ("number", "count", "string", "bool", "names", "map", "groups", "poses", "twists",
             "choice", "values", "wrenches", "points", "blob", "cameras")
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


# A client's timeout for a long-running operation (one that steps the world) by default.
LONG_RUNNING_TIMEOUT_S = 600.0


@dataclass(frozen=True)
class Operation:
    """One operation: its arguments, what it does to a world and how long a client waits.

    ``fast``: answered on the transport's thread from the last published state, without
    waiting for the physics thread. ``steps``: long-running, answered only when its steps
    are done (it belongs to its client, who may wait ``LONG_RUNNING_TIMEOUT_S``).
    ``timeout_floor_s``: the least a client should wait for it (rebuilding a world takes
    seconds), whatever its default timeout.
    """

    name: str
    args: tuple[Arg, ...] = ()
    mutates: bool = False
    steps: bool = False
    fast: bool = False
    timeout_floor_s: float = 0.0

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


_NAMES = Arg("names", "names", required=True)
_REBUILDS = 30.0  # operations that may rebuild the engine's world wait at least this long
OPERATIONS: dict[str, Operation] = {op.name: op for op in (
    Operation("status", fast=True),
    Operation("capabilities"),
    Operation("play", (Arg("rtf", "number"),), mutates=True),
    Operation("set_rtf", (Arg("rtf", "number", required=True),), mutates=True),
    Operation("pause", mutates=True),
    Operation("stop", mutates=True),
    Operation("step", (Arg("count", "count"), Arg("read", "names"), Arg("read_joints", "names")),
              mutates=True, steps=True),
    Operation("run_until", (Arg("sim_time", "number", required=True), Arg("read", "names"),
                            Arg("until_rest", "map"), Arg("read_joints", "names")),
              mutates=True, steps=True),
    Operation("reset", (Arg("scope", "choice", choices=("time", "state", "spawned", "all")),),
              mutates=True),
    Operation("load_world", (Arg("engine", "choice", required=True,
                                 choices=ENGINE_NAMES), Arg("params", "map")),
              mutates=True, timeout_floor_s=_REBUILDS),
    Operation("spawn", (Arg("groups", "groups", required=True),), mutates=True,
              timeout_floor_s=_REBUILDS),
    Operation("load_model", (Arg("format", "choice", required=True, choices=("mjcf", "urdf")),
                             Arg("text", "string", long_text=True), Arg("path", "string"),
                             Arg("prefix", "string"), Arg("fixed_base", "bool"),
                             Arg("search_path", "string")), mutates=True,
              timeout_floor_s=_REBUILDS),
    Operation("list", (Arg("name", "string"), Arg("tag", "string"),
                       Arg("kind", "choice", choices=("static", "dynamic")))),
    Operation("get_states", (Arg("names", "names"),)),
    Operation("set_states", (_NAMES, Arg("poses", "poses"), Arg("twists", "twists")),
              mutates=True),
    Operation("update", (_NAMES, Arg("properties", "map", required=True)), mutates=True),
    Operation("delete", (_NAMES,), mutates=True, timeout_floor_s=_REBUILDS),
    Operation("joints", (Arg("model", "string"), Arg("names", "names"))),
    Operation("get_joint_states", (Arg("names", "names"),)),
    Operation("set_joint_states", (_NAMES, Arg("positions", "values", required=True),
                                   Arg("velocities", "values"), Arg("read", "names")),
              mutates=True),
    Operation("set_joint_targets", (_NAMES, Arg("mode", "choice", required=True,
                                                choices=TARGET_MODES),
                                    Arg("targets", "values"), Arg("kp", "values"),
                                    Arg("kd", "values"), Arg("max_effort", "values")),
              mutates=True),
    Operation("apply_wrench", (_NAMES, Arg("wrenches", "wrenches", required=True),
                               Arg("points", "points"), Arg("duration", "number")),
              mutates=True),
    Operation("clear_wrenches", (Arg("names", "names"),), mutates=True),
    Operation("snapshot", (Arg("slot", "string"), Arg("blob", "bool"))),
    Operation("restore", (Arg("slot", "string"), Arg("blob", "blob", long_text=True)),
              mutates=True, timeout_floor_s=_REBUILDS),
    Operation("snapshots"),
    Operation("delete_snapshot", (Arg("slot", "string", required=True),)),
    Operation("list_worlds"),
    Operation("create_world", (Arg("name", "string", required=True),
                               Arg("engine", "choice", choices=ENGINE_NAMES),
                               Arg("params", "map")), timeout_floor_s=_REBUILDS),
    Operation("fork_world", (Arg("name", "string", required=True), Arg("source", "string")),
              timeout_floor_s=_REBUILDS),
    Operation("delete_world", (Arg("name", "string", required=True),)),
    Operation("predict", (Arg("horizon", "number", required=True), Arg("every", "number"),
                          Arg("read", "names"), Arg("read_joints", "names"),
                          Arg("slot", "string"), Arg("set_states", "map"),
                          Arg("joint_targets", "map"), Arg("wrenches", "map")),
              steps=True),
    Operation("compare", (_NAMES, Arg("poses", "poses", required=True), Arg("twists", "twists"),
                          Arg("sigma_position", "number"), Arg("sigma_angle", "number"),
                          Arg("sigma_speed", "number"), Arg("correct", "bool")),
              mutates=True),
    Operation("render", (Arg("cameras", "cameras", required=True),
                         Arg("format", "choice", choices=("raw", "png")))),
    Operation("add_camera", (Arg("name", "string", required=True),
                             Arg("camera", "map", required=True)), mutates=True),
    Operation("remove_camera", (Arg("name", "string", required=True),), mutates=True),
    Operation("cameras"),
    Operation("raycast", (Arg("origins", "points", required=True), Arg("directions", "points"),
                          Arg("ends", "points"), Arg("max_length", "number"))),
    Operation("contacts", (Arg("names", "names"),)),
    Operation("get_params"),
    Operation("set_params", (Arg("params", "map", required=True),), mutates=True),
    # The control lease (daemon/access/lease.py): they change who may mutate, not the world.
    Operation("take_control"),
    Operation("release_control"),
    # State streams (daemon/world/state_streams.py): poses published at a client's rate.
    Operation("stream_states", (Arg("rate", "number"), Arg("names", "names"))),
    Operation("close_stream", (Arg("stream", "string", required=True),)),
)}


def operation(name: str) -> Operation:
    """The operation of that name, or UnknownOperationError with the closest names."""
    found = OPERATIONS.get(name)
    if found is None:
        known = sorted(OPERATIONS)
        raise UnknownOperationError(
            f"unknown operation {name[:64]!r}{did_you_mean(name[:64], known)}",
            {"operations": known})
    return found
