"""docs/protocol.md, read as a user who has only that page: each promise below is a request
the page describes, sent as raw msgpack over the client's transport, and the reply the
page says it gets (its code, `details`, result fields, message). One test per transport
and engine runs them all on one world and lists every promise broken, so one run shows
every mismatch at once. The promises other tests hold (test_bad_input, test_robustness,
test_protocol_doc, ...) are not repeated here."""

from __future__ import annotations

import queue
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import msgpack
import numpy as np
import pytest
from support import ball_row, raw_replies, snapshot

from galton.client import Client, EmbeddedDaemon
from galton.client.sdk.telemetry import Subscription
from galton.client.transport.discovery import wait_for_daemon
from galton.protocol import ControlHeldError, ResultCode, pack_f64
from galton.protocol.operations import OPERATIONS

OK, NOT_FOUND = ResultCode.OK, ResultCode.NOT_FOUND
INCORRECT_STATE, FEATURE_UNSUPPORTED = ResultCode.INCORRECT_STATE, ResultCode.FEATURE_UNSUPPORTED
INVALID, MALFORMED = ResultCode.INVALID_ARGUMENT, ResultCode.MALFORMED_REQUEST
VERSION, LIMIT = ResultCode.UNSUPPORTED_VERSION, ResultCode.RESOURCE_LIMIT
PRESENT = object()  # a `details` key whose value the page does not fix

# The engines named in docs/protocol.md (capabilities.engine, create_world, load_world).
DOC_ENGINES = {"mujoco", "pybullet", "ode", "dart"}
# Another engine's parameter (get_params / set_params: FEATURE_UNSUPPORTED).
FOREIGN_PARAM = {"mujoco": "pybullet.collision_margin", "pybullet": "mujoco.impratio"}
RENDER_BACKENDS = {"mujoco": {"egl", "osmesa"}, "pybullet": {"tinyrenderer"}}
CAMERA = {"eye": [1.0, 0.0, 1.0], "target": [0.0, 0.0, 0.0], "width": 8, "height": 8}


@dataclass(frozen=True)
class Promise:
    """One request the page describes and what it says comes back."""

    section: str
    op: str
    args: dict[str, Any] | Callable[[str], dict[str, Any]] | None = None
    code: ResultCode | dict[str, ResultCode] = OK   # or one per transport
    details: dict[str, Any] = field(default_factory=dict)
    result: dict[str, Any] = field(default_factory=dict)  # fields and values (PRESENT: any)
    message: tuple[str, ...] = ()
    envelope: dict[str, Any] | None = None  # sent as it is, instead of {v, op, args}
    check: Callable[[dict[str, Any], str], str | None] | None = None  # more, per engine
    before: tuple[tuple[str, dict[str, Any]], ...] = ()  # sent first, each answered OK


def engines_md_formats(engine: str) -> set[str]:
    """docs/ENGINES.md's "Model formats:" line under the engine's heading."""
    page = (Path(__file__).resolve().parents[2] / "docs" / "ENGINES.md").read_text()
    section = page.split(f"\n## {engine} ")[1].split("\n## ")[0]
    line = re.search(r"Model formats: ([\w, ]+)", section)
    assert line, f"docs/ENGINES.md: no model formats for {engine}"
    return {name.strip() for name in line.group(1).split(",")}


def capabilities_as_told(result: dict[str, Any], engine: str) -> str | None:
    host = {"cpu_model", "logical_cores", "memory_bytes", "os", "hostname", "python",
            "engines"}
    problems = [
        result["engine"] not in DOC_ENGINES and f"engine {result['engine']!r}",
        result["protocol_version"] != 1 and "protocol_version",
        set(result["model_formats"]) != engines_md_formats(engine) and "model_formats",
        set(result["zmq"]) < {"control", "telemetry"} and f"zmq {result['zmq']}",
        not host <= set(result["host"]) and f"host {sorted(result['host'])}",
        result["render_backend"] not in RENDER_BACKENDS[engine]
        and f"render_backend {result['render_backend']!r}",
        not set(result["engines_available"]) <= DOC_ENGINES and "engines_available",
        not {"spawn_inertia", "model_shapes"} <= set(result["features"]) and "features",
        not {"sphere", "box", "cylinder", "capsule", "plane"} <= set(result["body_shapes"])
        and "body_shapes",
        any(set(spec) != {"default", "unit", "doc", "source"}
            for spec in result["params"].values()) and "params' {default, unit, doc, source}",
    ]
    return ", ".join(p for p in problems if p) or None


SHARED_PARAMS = {"timestep", "gravity", "solver_iterations", "default_friction",
                 "default_restitution", "default_static_friction", "default_static_restitution"}


def shared_params(result: dict[str, Any], engine: str) -> str | None:
    params = result["params"]
    missing = SHARED_PARAMS - set(params)
    if missing:
        return f"no shared parameter {sorted(missing)}"
    return None if list(params["gravity"]) == [0, 0, -9.81] else f"gravity {params['gravity']}"


def rows_of(key: str, fields: set[str]) -> Callable[[dict[str, Any], str], str | None]:
    def check(result: dict[str, Any], engine: str) -> str | None:
        bad = [row for row in result[key] if set(row) != fields]
        return f"{key} rows {bad}" if bad else None
    return check


def samples(count: int) -> Callable[[dict[str, Any], str], str | None]:
    def check(result: dict[str, Any], engine: str) -> str | None:
        return None if len(result["times"]) == 8 * count else f"times {result['times']!r}"
    return check


def engine_is_told(result: dict[str, Any], engine: str) -> str | None:
    return None if result.get("engine") == engine else f"engine {result.get('engine')!r}"


PROMISES: dict[str, Promise] = {
    # Requests: the envelope.
    "a request without v is UNSUPPORTED_VERSION, details.supported": Promise(
        "Requests", "status", envelope={"op": "status"}, code=VERSION,
        details={"supported": PRESENT}),
    "v 2 with an unknown op is UNSUPPORTED_VERSION (the order of checks)": Promise(
        "Which check comes first", "explode", envelope={"v": 2, "op": "explode"},
        code=VERSION),
    "op may be omitted over Zenoh, is required over ZeroMQ": Promise(
        "Requests; ZeroMQ", "status", envelope={"v": 1},
        code={"zenoh": OK, "zmq": MALFORMED}),
    "args not a map is MALFORMED_REQUEST": Promise(
        "Which check comes first", "status", envelope={"v": 1, "op": "status", "args": [1]},
        code=MALFORMED),
    "a client id holding * is refused": Promise(
        "Requests", "status", envelope={"v": 1, "op": "status", "client": "a*"},
        code=INVALID, message=("client",)),
    "a client id starting with @ is refused": Promise(
        "Requests", "list", envelope={"v": 1, "op": "list", "client": "@zmq:0:x"},
        code=INVALID, message=("client",)),
    "an unknown operation suggests close ones": Promise(
        "Result codes", "stpe", code=ResultCode.UNKNOWN_OPERATION, message=("step",)),
    "an unknown world is NOT_FOUND with a did you mean": Promise(
        "Requests", "status", {"world": "defualt"}, code=NOT_FOUND,
        message=("did you mean", "default")),
    "a wrong type names op.field and quotes the value": Promise(
        "Operations", "step", {"count": "ten"}, code=INVALID,
        message=("step.count must be int, got 'ten'",)),
    "an out-of-range value names the range": Promise(
        "Operations", "predict", {"horizon": 0}, code=INVALID,
        message=("predict.horizon must be a finite number > 0, got 0",)),
    # Limits.
    "a string past max_string_bytes: details limit and max": Promise(
        "Limits", "status", {"world": "w" * 5000}, code=LIMIT,
        details={"limit": "max_string_bytes", "max": 4096}),
    "nesting past max_depth: details limit and max": Promise(
        "Limits", "status", {"world": [[[[[[[[[[[[[[[[[[["deep"]]]]]]]]]]]]]]]]]]]},
        code=LIMIT, details={"limit": "max_depth", "max": 16}),
    "a step past max_steps is INVALID_ARGUMENT, as a range": Promise(
        "Limits", "step", {"count": 10**9 + 1}, code=INVALID, message=("step.count",)),
    "run_until far away names run_until.sim_time, details.max_steps": Promise(
        "run_until", "run_until", {"sim_time": 1e308}, code=INVALID,
        details={"max_steps": 10**9}, message=("run_until.sim_time",)),
    # Bounds.
    "a position past 1e9 m names its field, details field and max": Promise(
        "Bounds", "set_states",
        {"names": ["ball_0"], "poses": pack_f64(np.array([[2e9, 0, 1, 0, 0, 0, 1]]))},
        code=INVALID, details={"field": PRESENT, "max": PRESENT}),
    # Operations' replies.
    "capabilities: its fields as the table tells them": Promise(
        "capabilities", "capabilities", check=capabilities_as_told),
    "status: nobody controls, nothing steps, the live world": Promise(
        "status", "status", result={"controller": None, "stepping": False,
                                    "world": "default", "state": "stopped"},
        check=engine_is_told),
    "list's name is a glob": Promise(
        "list", "list", {"name": "ball_?"}, check=lambda r, e: None if sorted(
            x["name"] for x in r["entities"]) == ["ball_0", "ball_1"] else str(r)),
    "get_entities' pattern globs as list's name": Promise(
        "get_entities", "get_entities", {"pattern": "ball_?"},
        result={"names": ["ball_0", "ball_1"]}),
    "get_entities: a pattern not a string is INVALID_ARGUMENT naming it": Promise(
        "get_entities", "get_entities", {"pattern": 3}, code=INVALID, message=("pattern",)),
    "get_entities: a region whose min exceeds its max is INVALID_ARGUMENT": Promise(
        "get_entities", "get_entities",
        {"region": pack_f64(np.array([[1.0, 1, 1], [0, 0, 0]]))}, code=INVALID),
    "get_bounds: an unknown name is NOT_FOUND": Promise(
        "get_bounds", "get_bounds", {"names": ["ghost"]}, code=NOT_FOUND),
    "get_shapes: an unknown name is NOT_FOUND": Promise(
        "get_shapes", "get_shapes", {"names": ["ghost"]}, code=NOT_FOUND),
    "load_model: a device is INVALID_ARGUMENT": Promise(
        "load_model", "load_model", {"format": "urdf", "path": "/dev/zero"}, code=INVALID),
    "load_model: text and path both is INVALID_ARGUMENT": Promise(
        "load_model", "load_model", {"format": "urdf", "path": "/x.urdf", "text": "<robot/>"},
        code=INVALID),
    "load_model: sdf is FEATURE_UNSUPPORTED naming the formats": Promise(
        "load_model", "load_model", {"format": "sdf", "text": "<sdf/>"},
        code=FEATURE_UNSUPPORTED, message=("mjcf", "urdf")),
    "joints: an unknown joint is NOT_FOUND": Promise(
        "joints", "joints", {"names": ["ghost"]}, code=NOT_FOUND),
    "snapshot with neither slot nor blob is refused": Promise(
        "snapshot", "snapshot", {}, code=INVALID),
    "restore with slot and blob both is refused": Promise(
        "restore", "restore", {"slot": "a", "blob": b"x"}, code=INVALID),
    "restore of an unknown slot is NOT_FOUND": Promise(
        "restore", "restore", {"slot": "nowhere"}, code=NOT_FOUND),
    "restore of a corrupt blob is INVALID_ARGUMENT": Promise(
        "restore", "restore", {"blob": b"\x81\xa1a\x01"}, code=INVALID),
    "delete_snapshot of an unknown slot is NOT_FOUND": Promise(
        "delete_snapshot", "delete_snapshot", {"slot": "nowhere"}, code=NOT_FOUND),
    "delete_world of the live world is INVALID_ARGUMENT": Promise(
        "delete_world", "delete_world", {"name": "default"}, code=INVALID),
    "remove_camera of an unknown camera is NOT_FOUND": Promise(
        "remove_camera", "remove_camera", {"name": "nowhere"}, code=NOT_FOUND),
    "render of an unknown camera is NOT_FOUND": Promise(
        "render", "render", {"cameras": [{"camera": "nowhere"}]}, code=NOT_FOUND),
    "render: a bad camera is INVALID_ARGUMENT naming its field": Promise(
        "render", "render", {"cameras": [dict(CAMERA, fov=180)]}, code=INVALID,
        message=("fov",)),
    "raycast: directions and ends both is refused": Promise(
        "raycast", "raycast", {"origins": pack_f64(np.zeros((1, 3))),
                               "directions": pack_f64(np.ones((1, 3))),
                               "ends": pack_f64(np.ones((1, 3)))}, code=INVALID),
    "raycast: neither directions nor ends is refused": Promise(
        "raycast", "raycast", {"origins": pack_f64(np.zeros((1, 3)))}, code=INVALID),
    "raycast: one entry per ray": Promise(
        "raycast", "raycast", {"origins": pack_f64(np.array([[0.0, 0, 3]])),
                               "directions": pack_f64(np.array([[0.0, 0, -1]]))},
        result={"entities": ["ball_0"], "hits": b"\x01"}),
    "another engine's parameter is FEATURE_UNSUPPORTED": Promise(
        "get_params / set_params", "set_params",
        lambda engine: {"params": {FOREIGN_PARAM[engine]: 0.01}}, code=FEATURE_UNSUPPORTED),
    "an unknown parameter is INVALID_ARGUMENT with suggestions": Promise(
        "get_params / set_params", "set_params", {"params": {"gravty": [0, 0, -9.81]}},
        code=INVALID, message=("gravity",)),
    "step has no until_rest": Promise(
        "run_until", "step", {"count": 1, "until_rest": {"speed": 1, "every": 1}},
        code=INVALID, message=("until_rest",)),
    "until_rest needs read": Promise(
        "run_until", "run_until", {"sim_time": 1.0, "until_rest": {"speed": 1, "every": 1}},
        code=INVALID),
    "stream_states: a rate past 60 is INVALID_ARGUMENT": Promise(
        "stream_states", "stream_states", {"rate": 61}, code=INVALID),
    "close_stream of no open stream is NOT_FOUND": Promise(
        "stream_states", "close_stream", {"stream": "nowhere"}, code=NOT_FOUND),
    "play of a side world that does not exist is NOT_FOUND": Promise(
        "Worlds", "play", {"world": "side"}, code=NOT_FOUND),
    "take_control without client: INVALID_ARGUMENT over Zenoh, the connection's over ZeroMQ":
        Promise("take_control", "take_control",
                code={"zenoh": INVALID, "zmq": OK}),
    "release_control: released, controller nil": Promise(
        "take_control", "release_control", result={"controller": None}),
    "release_control when nobody holds it is no error": Promise(
        "take_control", "release_control", result={"controller": None, "released": False}),
    "clear_wrenches without names counts every entity": Promise(
        "clear_wrenches", "clear_wrenches", result={"count": 2}),
    "an invalid client is checked before the operation exists": Promise(
        "Which check comes first", "explode",
        envelope={"v": 1, "op": "explode", "client": "a*"}, code=INVALID),
    "get_params: the shared names, gravity (0, 0, -9.81)": Promise(
        "get_params / set_params; Conventions", "get_params", check=shared_params),
    "list_worlds: each row's fields": Promise(
        "list_worlds", "list_worlds", check=rows_of("worlds", {
            "name", "live", "engine", "state", "step", "sim_time", "entity_count",
            "faulted"})),
    "contacts: its fields": Promise(
        "contacts", "contacts", result={"count": 0, "a": [], "b": [], "positions": PRESENT,
                                        "normals": PRESENT, "forces": PRESENT,
                                        "penetrations": PRESENT}),
    "compare at the created pose scores 0": Promise(
        "compare", "compare",
        {"names": ["ball_0"], "poses": pack_f64(np.array([[0.0, 0, 1, 0, 0, 0, 1]]))},
        result={"score": 0.0, "corrected": False, "position_errors": pack_f64(np.zeros(1)),
                "angle_errors": pack_f64(np.zeros(1))}),
    "predict: an every past the horizon samples the present and the end": Promise(
        "predict", "predict", {"horizon": 0.02, "every": 5.0, "read": ["ball_0"]},
        result={"names": ["ball_0"]}, check=samples(2)),
    "predict: a horizon under one step is INVALID_ARGUMENT": Promise(
        "predict", "predict", {"horizon": 1e-7}, code=INVALID),
    "snapshot to a slot: its fields": Promise(
        "snapshot", "snapshot", {"slot": "doc-promise"},
        result={"slot": "doc-promise", "world": "default", "entity_count": 2,
                "bytes": PRESENT, "step": 0, "sim_time": 0.0}),
    "snapshots: each slot's fields": Promise(
        "snapshots", "snapshots", check=rows_of("slots", {
            "slot", "world", "engine", "bytes", "step", "sim_time", "entity_count"})),
    "delete_snapshot: count 1": Promise(
        "delete_snapshot", "delete_snapshot", {"slot": "doc-promise"}, result={"count": 1}),
    "fork_world: the new world's row": Promise(
        "fork_world", "fork_world", {"name": "fork"},
        result={"name": "fork", "live": False, "entity_count": 2}),
    "delete_world of the fork: count 1": Promise(
        "delete_world", "delete_world", {"name": "fork"}, result={"count": 1}),
    "cameras: none in a fresh world": Promise("cameras", "cameras", result={"cameras": []}),
    "a 33rd camera: RESOURCE_LIMIT, details.limit cameras, details.max 32": Promise(
        "add_camera", "add_camera", {"name": "c32", "camera": CAMERA}, code=LIMIT,
        details={"limit": "cameras", "max": 32},
        before=tuple(("add_camera", {"name": f"c{i}", "camera": CAMERA}) for i in range(32))),
    "cameras: each with its name": Promise(
        "cameras", "cameras", check=lambda r, e: None if len(r["cameras"]) == 32 and all(
            c["name"].startswith("c") for c in r["cameras"]) else str(r)[:200]),
    "render: images, labels and the format asked": Promise(
        "render", "render", {"cameras": [CAMERA]},
        result={"format": "raw", "labels": PRESENT},
        check=lambda r, e: None if (r["images"][0]["width"], r["images"][0]["height"],
                                    len(r["images"][0]["rgb"])) == (8, 8, 192)
        else str(r["images"])[:200]),
    "stream_states without client: INVALID_ARGUMENT over Zenoh, the connection's over ZeroMQ":
        Promise("stream_states", "stream_states", {"rate": 5},
                code={"zenoh": INVALID, "zmq": OK},
                result={"rate": 5.0, "world": "default", "silence_s": 10.0,
                        "stream": PRESENT, "key": PRESENT, "topic": PRESENT}),
    "spawn: a taken name is NAME_NOT_UNIQUE, details.taken": Promise(
        "spawn", "spawn", {"groups": [ball_row(1)[1].to_wire()]},
        code=ResultCode.NAME_NOT_UNIQUE, details={"taken": ["ball_0"]}),
    "spawn: a name of 129 characters is refused": Promise(
        "Conventions", "spawn", {"groups": [ball_row(1, prefix="n" * 127)[1].to_wire()]},
        code=INVALID),
    "spawn: a size past 10^4 m is refused": Promise(
        "spawn", "spawn", {"groups": [dict(ball_row(1, prefix="huge")[1].to_wire(),
                                           size=[2e4])]}, code=INVALID),
    "spawn: a static body's twist must be zero": Promise(
        "spawn", "spawn", {"groups": [dict(ball_row(1, prefix="still")[1].to_wire(),
                                           static=True,
                                           twists=pack_f64(np.array([[1.0, 0, 0, 0, 0, 0]])))]},
        code=INVALID),
    "update: friction out of [0, 100] names update.properties.friction": Promise(
        "update", "update", {"names": ["ball_0"], "properties": {"friction": 101}},
        code=INVALID, message=("update.properties.friction",)),
    "apply_wrench: a duration of 0 is refused": Promise(
        "apply_wrench", "apply_wrench", {"names": ["ball_0"],
                                         "wrenches": pack_f64(np.zeros((1, 6))),
                                         "duration": 0}, code=INVALID),
    "apply_wrench: a wrong number of rows is refused": Promise(
        "apply_wrench", "apply_wrench", {"names": ["ball_0"],
                                         "wrenches": pack_f64(np.zeros((2, 6)))},
        code=INVALID),
    "joints: none in a world without models": Promise("joints", "joints",
                                                      result={"joints": []}),
    "render: png when asked": Promise(
        "render", "render", {"cameras": [CAMERA], "format": "png"}, result={"format": "png"},
        check=lambda r, e: None if bytes(r["images"][0]["rgb"]).startswith(b"\x89PNG")
        else "not a png"),
    # Changes come last: they move the world the refusals above were checked against.
    "create_world: its row of list_worlds": Promise(
        "create_world", "create_world", {"name": "side"},
        result={"name": "side", "live": False, "entity_count": 0, "faulted": False}),
    "a side world never plays": Promise(
        "Worlds", "play", {"world": "side"}, code=INCORRECT_STATE),
    "a side world takes no set_rtf": Promise(
        "Worlds", "set_rtf", {"rtf": 2.0, "world": "side"}, code=INCORRECT_STATE),
    "delete_world: count 1": Promise(
        "delete_world", "delete_world", {"name": "side"}, result={"count": 1}),
    "an argument sent as nil takes its default": Promise(
        "Operations", "step", {"count": None}, result={"steps": 1}),
    "the Example: step 500": Promise("Example", "step", {"count": 500}, result={"steps": 500}),
    "a stepped stopped world is paused": Promise(
        "step", "status", result={"state": "paused", "step": 501}),
    "reset all keeps a paused world paused, at time 0, empty": Promise(
        "reset", "reset", {"scope": "all"},
        result={"state": "paused", "step": 0, "entity_count": 0}),
    "stop: stopped at time 0": Promise("stop", "stop", result={"state": "stopped", "step": 0}),
    "pause from stopped gives paused at time 0": Promise(
        "stop", "pause", result={"state": "paused", "step": 0, "sim_time": 0.0}),
}


def wire(promise: Promise, engine: str) -> bytes:
    """The request's bytes, as a client with only the page would write them."""
    if promise.envelope is not None:
        return bytes(msgpack.packb(promise.envelope, use_bin_type=True))
    args = promise.args(engine) if callable(promise.args) else promise.args
    envelope: dict[str, Any] = {"v": 1, "op": promise.op}
    if args is not None:
        envelope["args"] = args
    return bytes(msgpack.packb(envelope, use_bin_type=True))


def reply_shape(reply: dict[str, Any]) -> list[str]:
    """Replies: every reply carries these fields, of these types (the Replies table)."""
    problems = []
    kinds = {"v": int, "code": int, "code_name": str, "message": str, "result": dict,
             "step": int, "sim_time": float}
    for name, kind in kinds.items():
        if not isinstance(reply.get(name), kind):
            problems.append(f"reply field {name} is {reply.get(name)!r}")
    if reply.get("v") != 1:
        problems.append("reply v is not 1")
    if reply.get("code_name") != ResultCode(reply["code"]).name:
        problems.append(f"code_name {reply.get('code_name')} for code {reply['code']}")
    if reply["code"] != OK and (reply["result"] or not isinstance(reply.get("details"), dict)):
        problems.append("a failure's result is not empty or its details not a map")
    if len(reply.get("message", "")) > 2000:
        problems.append("message longer than 2,000 characters")
    return problems


def broken(promise: Promise, reply: dict[str, Any], transport: str, engine: str) -> list[str]:
    """How this reply breaks the promise (nothing when it keeps it)."""
    code = promise.code[transport] if isinstance(promise.code, dict) else promise.code
    if reply["code"] != code:
        return [f"code {reply.get('code_name')} ({reply.get('message')!r}), page says "
                f"{code.name}"]
    problems = reply_shape(reply)
    details = reply.get("details") or {}
    for key, value in promise.details.items():
        if key not in details or (value is not PRESENT and details[key] != value):
            problems.append(f"details {details}, page says {key}={value!r}")
    for key, value in (promise.result if code == OK else {}).items():
        if key not in reply["result"] or (value is not PRESENT and reply["result"][key] != value):
            problems.append(f"result {key}={reply['result'].get(key)!r}, page says {value!r}")
    problems += [f"message lacks {m!r}: {reply['message']!r}" for m in promise.message
                 if m not in reply["message"]]
    if promise.check is not None and code == OK:
        problems += [p for p in [promise.check(reply["result"], engine)] if p]
    return problems


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])  # one per transport (conftest)
def test_every_promise_of_the_page_holds(sim: Client, engine: str, transport: str) -> None:
    sim.spawn(ball_row(2)[1])
    failures = keeps_every_promise(sim, PROMISES, transport, engine)
    assert not failures, "\n".join(failures)


PAGE = (Path(__file__).resolve().parents[2] / "docs" / "protocol.md").read_text()
EVENTS_WAIT_S = 20.0


def events_table() -> dict[str, tuple[set[str], dict[str, set[str]]]]:
    """Events: each kind's fields as the page's table gives them: those every event of the
    kind carries, and those it adds for one operation ("`scope` for `reset`")."""
    table = {}
    for kind, cell in re.findall(r"^\| `(\w+)` \| ([^|]+) \|", PAGE.split("## Events")[1],
                                 re.MULTILINE):
        always, _, extras = cell.partition("(")
        per_op = {op: set(re.findall(r"`(\w+)`", told)) for told, op in
                  re.findall(r"((?:`\w+`(?: and )?)+) for `(\w+)`", extras)}
        table[kind] = (set(re.findall(r"`(\w+)`", always)), per_op)
    return table


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])  # one per transport (conftest)
def test_every_event_carries_the_fields_of_the_table(sim: Client, engine: str) -> None:
    table = events_table()
    seen: queue.Queue[dict[str, Any]] = queue.Queue()
    with sim.on_event(seen.put):
        names, group = ball_row(1)
        sim.spawn(group)
        sim.compare(names, np.array([[0.0, 0, 1, 0, 0, 0, 1]]))
        sim.fork_world("fork")
        sim.delete_world("fork")
        sim.take_control()
        sim.release_control()
        sim.step(1)
        sim.reset("state")
        sim.load_world(engine)
        events = []
        while not any(e.get("op") == "load_world" for e in events):
            events.append(seen.get(timeout=EVENTS_WAIT_S))
    assert {e["kind"] for e in events} >= {"scene", "world", "control", "state"}
    for event in events:
        always, per_op = table[event["kind"]]
        told = {"instance", "seq", "kind"} | always | per_op.get(event.get("op", ""), set())
        assert told <= set(event), (event, told - set(event))


# Limits, each set lower with --limit NAME=VALUE: a request just over it, and what must
# still hold after its refusal (the limits the default suite cannot reach cheaply).
LOWERED = {"max_entities": 3, "max_model_bytes": 300, "max_worlds": 2, "max_request_bytes": 4096}
URDF = ('<robot name="r"><link name="base"><inertial><mass value="1"/><inertia ixx="1" '
        'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>')


def test_each_limit_lowered_is_refused_by_name_and_value(tmp_path: Path) -> None:
    """Limits: `--limit NAME=VALUE` sets it; over it, RESOURCE_LIMIT with details.limit
    naming it and details.max its value, and nothing changed."""
    big_model = tmp_path / "big.urdf"
    big_model.write_text(URDF + " " * 400)
    over = {
        "max_entities": ("spawn", {"groups": [ball_row(2, prefix="more")[1].to_wire()]}),
        "max_model_bytes": ("load_model", {"format": "urdf", "text": URDF + " " * 400}),
        "max_worlds": ("create_world", {"name": "second"}),
        "max_request_bytes": ("status", {"world": "w" * 3000, "tag": "t" * 3000}),
    }
    args = [part for name, value in LOWERED.items() for part in ("--limit", f"{name}={value}")]
    with EmbeddedDaemon("mujoco", instance="test-doc-limits", extra_args=args) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
        wait_for_daemon(sim.session, daemon.instance, 60.0)
        sim.spawn(ball_row(2)[1])
        sim.create_world("first")
        failures = []
        for name, (op, op_args) in [*over.items(), ("max_model_bytes (path)", (
                "load_model", {"format": "urdf", "path": str(big_model)}))]:
            limit = name.split()[0]
            before = snapshot(sim)
            sent = msgpack.packb({"v": 1, "op": op, "args": op_args}, use_bin_type=True)
            reply = msgpack.unpackb(raw_replies(sim, op, sent)[0])
            details = reply.get("details") or {}
            if (reply["code"], details.get("limit"), details.get("max")) != (
                    LIMIT, limit, LOWERED[limit]):
                failures.append(f"{name}: {reply['code_name']} {details} {reply['message']!r}")
            try:
                snapshot(sim).assert_same(before)
            except AssertionError:
                failures.append(f"{name}: the refusal changed the world")
        assert [w.name for w in sim.list_worlds()] == ["default", "first"]
        assert not failures, "\n".join(failures)


BOX_URDF = ('<robot name="r"><link name="base"><inertial><mass value="1"/><inertia ixx="1" '
            'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry>'
            '<box size="0.2 0.2 0.2"/></geometry></collision></link></robot>')


@pytest.mark.parametrize("engine", ["ode", "dart"])  # one per transport (conftest)
def test_ode_and_dart_answer_as_the_sections_that_name_them_say(sim: Client, engine: str
                                                                ) -> None:
    """get_bounds and get_entities' region: FEATURE_UNSUPPORTED for a loaded model on ODE
    and DART; get_shapes: all four answer (model_shapes); render: FEATURE_UNSUPPORTED where
    render_backend is nil; raycast where the features list it; model formats as
    docs/ENGINES.md lists them."""
    def call(op: str, args: dict[str, Any]) -> dict[str, Any]:
        sent = msgpack.packb({"v": 1, "op": op, "args": args}, use_bin_type=True)
        return dict(msgpack.unpackb(raw_replies(sim, op, sent)[0]))

    caps = call("capabilities", {})["result"]
    assert set(caps["model_formats"]) == engines_md_formats(engine)
    assert caps["render_backend"] is None and "render" not in caps["features"]
    assert call("load_model", {"format": "urdf", "text": BOX_URDF})["code"] == OK
    assert call("get_bounds", {})["code"] == FEATURE_UNSUPPORTED
    region = pack_f64(np.array([[-1.0, -1, -1], [1, 1, 1]]))
    assert call("get_entities", {"region": region})["code"] == FEATURE_UNSUPPORTED
    assert "model_shapes" in caps["features"]
    assert call("get_shapes", {})["result"]["kinds"] == ["box"]
    assert call("render", {"cameras": [CAMERA]})["code"] == FEATURE_UNSUPPORTED
    ray = {"origins": pack_f64(np.array([[0.0, 0, 3]])),
           "directions": pack_f64(np.array([[0.0, 0, -1]]))}
    cast = call("raycast", ray)
    if "raycast" in caps["features"]:
        assert cast["result"]["entities"] == ["base"]
    else:
        assert cast["code"] == FEATURE_UNSUPPORTED


def inertial(mass: float = 1.0) -> str:
    return (f'<inertial><mass value="{mass}"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" '
            'iyz="0" izz="0.01"/></inertial>')


ARM_URDF = (
    '<robot name="arm">'
    f'<link name="base">{inertial()}</link>'
    f'<link name="upper">{inertial()}<collision><geometry><box size="0.1 0.1 0.4"/>'
    '</geometry></collision></link>'
    f'<link name="tip">{inertial(0.1)}</link>'
    '<joint name="hinge" type="revolute"><parent link="base"/><child link="upper"/>'
    '<origin xyz="0 0 0.5"/><axis xyz="0 1 0"/>'
    '<limit lower="-1" upper="1" effort="10" velocity="2"/></joint>'
    '<joint name="weld" type="fixed"><parent link="upper"/><child link="tip"/>'
    '<origin xyz="0 0 0.4"/></joint>'
    '</robot>')

def shapeless_bounds(result: dict[str, Any], engine: str) -> str | None:
    """get_bounds: MuJoCo a box of no size at the body's origin, PyBullet the small box
    Bullet keeps round a link without a shape (about ±1 mm)."""
    low, high = np.frombuffer(result["bounds"]).reshape(2, 3)
    half = (high - low) / 2
    if engine == "mujoco" and not (np.all(half == 0) and np.allclose(low, 0)):
        return f"MuJoCo: {low} {high}, the page says a box of no size at the origin"
    if engine == "pybullet" and not np.all((half > 1e-4) & (half < 3e-3)):
        return f"PyBullet: {low} {high}, the page says about ±1 mm"
    return None


# An observation calibrate is given: two samples of one body, still (calibrate).
SEEN = {"times": pack_f64(np.array([0.0, 0.1])),
        "poses": pack_f64(np.tile([0.0, 0, 1, 0, 0, 0, 1], (2, 1)))}

JOINT_PROMISES: dict[str, Promise] = {
    "load_model: roots first, each before its links": Promise(
        "load_model", "load_model", {"format": "urdf", "text": ARM_URDF},
        result={"names": ["base", "upper", "tip"]}),
    "list: a model's shape, source and model": Promise(
        "load_model; list", "list", check=lambda r, e: None if [
            (x["name"], x["shape"], x["source"], x["model"], x["static"])
            for x in r["entities"]] == [
            ("base", "model", "model", "base", True), ("upper", "link", "model", "base", False),
            ("tip", "link", "model", "base", False)] else str(r["entities"])[:300]),
    "joints: the table's fields, in load order, mode none": Promise(
        "joints", "joints", check=lambda r, e: None if [
            (j["name"], j["type"], j["parent"], j["child"], j["lower"], j["upper"], j["mode"])
            for j in r["joints"]] == [
            ("hinge", "revolute", "base", "upper", -1.0, 1.0, "none"),
            ("weld", "fixed", "upper", "tip", None, None, "none")] else str(r["joints"])[:300]),
    "joints: an unknown joint is NOT_FOUND with a did you mean": Promise(
        "joints", "joints", {"names": ["hinje"]}, code=NOT_FOUND, message=("hinge",)),
    "get_joint_states: every 1-DOF joint when absent": Promise(
        "get_joint_states", "get_joint_states", result={"names": ["hinge"]}),
    "get_joint_states: a fixed joint is INVALID_ARGUMENT": Promise(
        "get_joint_states", "get_joint_states", {"names": ["weld"]}, code=INVALID),
    "set_joint_states: outside the limits, details joint, lower, upper": Promise(
        "set_joint_states", "set_joint_states", {"names": ["hinge"], "positions": 2.0},
        code=INVALID, details={"joint": "hinge", "lower": -1.0, "upper": 1.0}),
    "set_joint_states: one number for every name, read back": Promise(
        "set_joint_states", "set_joint_states",
        {"names": ["hinge"], "positions": 0.5, "read": ["tip"]},
        result={"count": 1, "names": ["tip"], "poses": PRESENT, "twists": PRESENT}),
    "set_joint_targets: a position target with kp 0 is refused": Promise(
        "set_joint_targets", "set_joint_targets",
        {"names": ["hinge"], "mode": "position", "targets": 0.2}, code=INVALID),
    "set_joint_targets: a position target outside the limits is refused": Promise(
        "set_joint_targets", "set_joint_targets",
        {"names": ["hinge"], "mode": "position", "targets": 3.0, "kp": 10.0}, code=INVALID),
    "set_joint_targets: max_effort 0 is refused": Promise(
        "set_joint_targets", "set_joint_targets",
        {"names": ["hinge"], "mode": "effort", "targets": 1.0, "max_effort": 0.0},
        code=INVALID),
    "set_joint_targets: a fixed joint is refused": Promise(
        "set_joint_targets", "set_joint_targets",
        {"names": ["weld"], "mode": "effort", "targets": 1.0}, code=INVALID),
    "set_joint_targets: held, and joints shows its mode": Promise(
        "set_joint_targets", "set_joint_targets",
        {"names": ["hinge"], "mode": "position", "targets": 0.2, "kp": 50.0, "kd": 5.0,
         "max_effort": float("inf")}, result={"count": 1}),
    "joints shows the mode": Promise(
        "set_joint_targets", "joints", {"names": ["hinge"]},
        check=lambda r, e: None if r["joints"][0]["mode"] == "position" else str(r)),
    "set_states of a link names its model": Promise(
        "load_model", "set_states",
        {"names": ["upper"], "poses": pack_f64(np.array([[0.0, 0, 1, 0, 0, 0, 1]]))},
        code=INVALID, message=("base",)),
    "delete of a link is refused": Promise(
        "load_model", "delete", {"names": ["tip"]}, code=INVALID, message=("base",)),
    "apply_wrench on a fixed-base root is refused": Promise(
        "apply_wrench", "apply_wrench", {"names": ["base"],
                                         "wrenches": pack_f64(np.zeros((1, 6)))},
        code=INVALID),
    "apply_wrench on a link: count": Promise(
        "apply_wrench", "apply_wrench", {"names": ["tip"],
                                         "wrenches": pack_f64(np.ones((1, 6)))},
        result={"count": 1}),
    "calibrate: bounds not low < high are INVALID_ARGUMENT": Promise(
        "calibrate", "calibrate", {"names": ["base"], **SEEN,
                                   "fit": {"hinge.damping": [1.0, 0.5]}}, code=INVALID,
        message=("low < high",)),
    "calibrate: a joint without one degree of freedom is INVALID_ARGUMENT": Promise(
        "calibrate", "calibrate", {"names": ["base"], **SEEN,
                                   "fit": {"weld.damping": [0.0, 1.0]}}, code=INVALID,
        message=("weld",)),
    "calibrate: a link observed without a slot is INVALID_ARGUMENT naming its model":
        Promise("calibrate", "calibrate", {
            "names": ["tip"], **SEEN,
            "fit": {"hinge.damping": [0.0, 1.0]}}, code=INVALID,
            message=("calibrate.names", "base")),
    "calibrate: an unknown body is NOT_FOUND": Promise(
        "calibrate", "calibrate", {"names": ["base"], **SEEN,
                                   "fit": {"ghost.friction": [0.0, 1.0]}}, code=NOT_FOUND),
    "a step, then efforts": Promise("get_joint_states", "step", {"count": 5,
                                                                 "read_joints": ["hinge"]},
                                    result={"steps": 5, "joints": PRESENT}),
    "stop sets every mode back to none": Promise("set_joint_targets", "stop"),
    "modes after stop": Promise(
        "set_joint_targets", "joints", check=lambda r, e: None if {
            j["mode"] for j in r["joints"]} == {"none"} else str(r["joints"])[:300]),
    "clear_wrenches after stop: the wrench went with stop, count all": Promise(
        "apply_wrench", "clear_wrenches", result={"count": 3}),
    "get_bounds: a model body with no collision shape, as each engine tells it": Promise(
        "get_bounds", "get_bounds", {"names": ["base"]}, check=shapeless_bounds),
    "delete of the root removes the model": Promise(
        "load_model", "delete", {"names": ["base"]}, result={"count": 1}),
    "and its joints": Promise("load_model", "joints", result={"joints": []}),
    "a capsule's half_length leaves its caps out": Promise(
        "Conventions; get_bounds", "get_bounds", {"names": ["pill"]},
        result={"bounds": pack_f64(np.array([[-0.1, -0.1, 0.7, 0.1, 0.1, 1.3]]))},
        before=(("spawn", {"groups": [{
            "shape": "capsule", "size": [0.1, 0.2], "names": ["pill"], "static": True,
            "poses": pack_f64(np.array([[0.0, 0, 1, 0, 0, 0, 1]]))}]}),)),
}


def keeps_every_promise(sim: Client, promises: dict[str, Promise], transport: str,
                        engine: str) -> list[str]:
    """Send each promise's request in turn; what each reply breaks."""
    failures = []
    for name, promise in promises.items():
        for op, args in promise.before:
            sent = msgpack.packb({"v": 1, "op": op, "args": args}, use_bin_type=True)
            assert msgpack.unpackb(raw_replies(sim, op, sent)[0])["code"] == OK, (name, op)
        before = snapshot(sim)
        replies = raw_replies(sim, promise.op, wire(promise, engine))
        if len(replies) != 1:
            failures.append(f"{name}: {len(replies)} replies, the page says one")
            continue
        reply = msgpack.unpackb(replies[0], raw=False)
        problems = broken(promise, reply, transport, engine)
        declared = OPERATIONS.get(promise.op)
        if reply["code"] != OK or not (declared and declared.mutates):
            try:
                snapshot(sim).assert_same(before)
            except AssertionError:
                problems.append("a rejected request, or a read, changed the world")
        failures += [f"{name} ({promise.section}): {p}" for p in problems]
    return failures


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])  # one per transport (conftest)
def test_every_promise_about_models_and_joints_holds(sim: Client, engine: str,
                                                     transport: str) -> None:
    failures = keeps_every_promise(sim, JOINT_PROMISES, transport, engine)
    assert not failures, "\n".join(failures)


@pytest.mark.parametrize("engine", ["mujoco"])
def test_a_wildcard_get_reaches_no_operation_and_discovery_finds_the_daemon(
        sim: Client, engine: str, transport: str) -> None:
    """Key expressions: the control chunk starts with `@`, so `galton/**` never reaches an
    operation; a liveliness get on `galton/*/alive` returns one key per daemon, its
    second chunk the instance name."""
    if transport != "zenoh":
        pytest.skip("Zenoh's key expressions")
    instance = sim.instance
    sim.spawn(ball_row(1)[1])
    before = snapshot(sim)
    reset = msgpack.packb({"v": 1, "args": {"scope": "all"}}, use_bin_type=True)
    for key in ("galton/**", f"galton/{instance}/**", f"galton/{instance}/*/reset"):
        assert list(sim.session.get(key, payload=reset, timeout=5.0)) == [], key
    snapshot(sim).assert_same(before)
    alive = [str(r.ok.key_expr) for r in sim.session.liveliness().get("galton/*/alive",
                                                                     timeout=5.0) if r.ok]
    assert f"galton/{instance}/alive" in alive


def telemetry_fields() -> set[str]:
    """Telemetry: the fields of the page's table."""
    table = PAGE.split("## Telemetry")[1].split("## Events")[0]
    return set(re.findall(r"^\| `(\w+)` \|", table, re.MULTILINE))


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])  # one per transport (conftest)
def test_telemetry_carries_the_table_s_fields_and_a_sample_per_world(sim: Client,
                                                                      engine: str) -> None:
    """Telemetry: one sample per world each period, `world` naming it; a side world's reads
    as its status does: stopped before its first step, rtf and target_rtf 0."""
    sim.create_world("quiet")
    samples: queue.Queue[dict[str, Any]] = queue.Queue()
    try:
        with Subscription(sim.transport.subscribe(
                "telemetry", lambda data: samples.put(msgpack.unpackb(data)))):
            seen: dict[str, dict[str, Any]] = {}
            while len(seen) < 2:
                sample = samples.get(timeout=EVENTS_WAIT_S)
                seen[sample["world"]] = sample
    finally:
        sim.delete_world("quiet")
    assert set(seen) == {"default", "quiet"}
    for sample in seen.values():
        assert set(sample) == telemetry_fields(), sample
    side = seen["quiet"]
    assert (side["state"], side["rtf"], side["target_rtf"], side["engine"]) == (
        "stopped", 0, 0, engine)


LONG_STEP = {"mujoco": 300_000, "pybullet": 1_000_000}  # about a second each, idle


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])  # one per transport (conftest)
def test_a_running_step_survives_another_client_taking_control(
        sim: Client, daemon: EmbeddedDaemon, engine: str, transport: str) -> None:
    """take_control: a step request already running when another client takes control
    runs to its end; the lease refuses only what is asked after it is taken, and an
    unknown argument is INVALID_ARGUMENT before the lease is looked at."""
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint
    done: queue.Queue[Any] = queue.Queue()
    with Client(daemon.instance, endpoint, timeout=20.0) as other:
        stepping = threading.Thread(target=lambda: done.put(sim.step(LONG_STEP[engine])))
        stepping.start()
        try:
            deadline = time.monotonic() + EVENTS_WAIT_S
            while not other.status().stepping and time.monotonic() < deadline:
                pass  # polling the daemon's own answer: no sleep
            assert other.take_control()
            assert other.status().stepping, "the step ended before control changed hands"
        finally:
            stepping.join(timeout=60.0)
        try:
            assert done.get(timeout=1.0).step == LONG_STEP[engine]  # every step asked
            with pytest.raises(ControlHeldError):
                sim.step(1)
            sent = msgpack.packb({"v": 1, "op": "spawn", "args": {"grops": []}},
                                 use_bin_type=True)
            refused = msgpack.unpackb(raw_replies(sim, "spawn", sent)[0])
            assert refused["code"] == INVALID and "groups" in refused["message"]
        finally:
            other.release_control()
