"""The declared requests (protocol/requests.py): what a bad one is told, and their JSON
Schema as `galton-client schema` prints it, checked against real requests."""

from __future__ import annotations

import base64
import json
import math
from typing import Any

import jsonschema
import numpy as np
import pytest
from typer.testing import CliRunner

from galton.client import spheres
from galton.client.cli.app import app
from galton.protocol import InvalidArgumentError, MalformedRequestError, pack_f64
from galton.protocol import replies as rp
from galton.protocol import requests as rq
from galton.protocol.operations import OPERATIONS
from galton.protocol.vocabulary import MAX_BATCH

REFUSED = {
    "wrong type": ("step", {"count": "ten"}, r"step\.count must be int, got 'ten'"),
    "bool is no number": ("play", {"rtf": True}, r"play\.rtf must be float, got True"),
    "unknown choice": ("reset", {"scope": "spawnd"},
                       r"reset\.scope 'spawnd' is not one of .*did you mean 'spawned'"),
    "missing field": ("set_states", {"poses": b""},
                      r"set_states: missing required field 'names'"),
    "unknown field": ("step", {"cuont": 3}, r"step takes no field 'cuont'.*did you mean 'count'"),
    "nested path": ("spawn", {"groups": ["x"]}, r"spawn\.groups\[0\] must be object, got 'x'"),
    "list item": ("delete", {"names": ["a", 7]}, r"delete\.names\[1\] must be str, got 7"),
    "above a range": ("set_rtf", {"rtf": 2e6},
                      r"set_rtf\.rtf must be a finite number in \[0, 1e\+06\], got 2000000\.0"),
    "NaN": ("play", {"rtf": math.nan}, r"play\.rtf must be a finite number in .*, got nan"),
    "infinity": ("predict", {"horizon": math.inf},
                 r"predict\.horizon must be a finite number > 0, got inf"),
    "zero horizon": ("predict", {"horizon": 0}, r"predict\.horizon must be .* > 0, got 0"),
    "count below one": ("step", {"count": 0}, r"step\.count must be an integer >= 1, got 0"),
    "rate": ("stream_states", {"rate": 61},
             r"stream_states\.rate must be a finite number in \[1, 60\], got 61"),
    "nested range": ("run_until", {"sim_time": 1, "until_rest": {"speed": -1, "every": 1}},
                     r"run_until\.until_rest\.speed must be a finite number > 0, got -1"),
    "nested unknown field": ("run_until", {"sim_time": 1, "until_rest": {"sped": 1, "every": 1}},
                             r"until_rest takes no field 'sped'.*did you mean 'speed'"),
    "no cameras": ("render", {"cameras": []},
                   r"render\.cameras must be a list of 1 to 16 items, got \[\]"),
    # Through a map's values (msgspec names no key): the value when the map holds one.
    "in a map": ("predict", {"horizon": 1, "perturb": {"bodies": {"a": {"velocity": "x"}}}},
                 r"predict\.perturb\.bodies\[\.\.\.\]\.velocity must be float, got 'x'$"),
    "in a map of several": ("predict", {"horizon": 1, "perturb": {"bodies": {
        "a": {"position": 0.1}, "b": {"position": 11}}}},
        r"perturb\.bodies\[\.\.\.\]\.position must be a finite number in \[0, 10\]$"),
    "unknown field in a map": ("predict", {"horizon": 1, "perturb": {"bodies": {"a": {
        "velo": 1}}}}, r"bodies\[\.\.\.\] takes no field 'velo'.*it takes: position, "),
    "list in a map": ("calibrate", {"names": ["a"], "times": b"", "poses": b"",
                                    "fit": {"a": [1, "x"]}},
                      r"calibrate\.fit\[\.\.\.\]\[1\] must be float, got 'x'"),
}


@pytest.mark.parametrize("op, args, message", REFUSED.values(), ids=REFUSED.keys())
def test_a_bad_request_is_told_what_and_where(op: str, args: dict[str, Any],
                                               message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        OPERATIONS[op].decode(args)


def test_a_good_request_decodes_to_its_declared_type() -> None:
    step = OPERATIONS["step"].decode({"count": 5, "read": ["a"], "world": "side"})
    assert isinstance(step, rq.Step)
    assert (step.count, step.read, step.read_joints, step.world) == (5, ["a"], None, "side")


def test_a_field_sent_as_nil_takes_its_declared_default() -> None:
    step = OPERATIONS["step"].decode({"count": None})
    assert isinstance(step, rq.Step) and step.count == 1
    stream = OPERATIONS["stream_states"].decode({})
    assert isinstance(stream, rq.StreamStates) and stream.rate == 10.0


def as_json(value: Any) -> Any:
    """A msgpack value as JSON carries it: bins as base64 strings."""
    if isinstance(value, bytes):
        return base64.b64encode(value).decode()
    if isinstance(value, dict):
        return {k: as_json(v) for k, v in value.items()}
    if isinstance(value, list):
        return [as_json(v) for v in value]
    return value


@pytest.fixture(scope="module")
def schema() -> dict[str, Any]:
    printed = CliRunner().invoke(app, ["schema"])
    assert printed.exit_code == 0, printed.output
    document: dict[str, Any] = json.loads(printed.output)
    assert set(document["operations"]) == set(OPERATIONS)
    return document


def validator(schema: dict[str, Any], op: str, part: str) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator({**schema["operations"][op][part],
                                            "$defs": schema["$defs"]})


def test_the_schema_takes_real_requests_and_refuses_bad_ones(schema: dict[str, Any]) -> None:
    group = spheres(["a", "b"], [[0, 0, 1], [1, 0, 1]], 0.1).to_wire()
    poses = pack_f64(np.tile([0, 0, 1, 0, 0, 0, 1.0], (2, 1)))
    good = {"spawn": {"groups": [group]}, "step": {"count": 10, "read": ["a"]},
            "set_states": {"names": ["a", "b"], "poses": poses}, "reset": {"scope": "all"},
            "get_bounds": {"names": ["a"], "world": "main"}}
    for op, args in good.items():
        OPERATIONS[op].decode(args)  # the daemon takes it ...
        validator(schema, op, "request").validate(as_json(args))  # ... and so does the schema
    bad = {"step": {"count": "ten"}, "reset": {"scope": "everything"},
           "set_states": {"poses": poses}, "get_bounds": {"nmaes": ["a"]}}
    for op, args in bad.items():
        assert not validator(schema, op, "request").is_valid(as_json(args)), op


def test_the_schema_shows_ranges_and_defaults(schema: dict[str, Any]) -> None:
    rate = schema["$defs"]["StreamStates"]["properties"]["rate"]
    assert (rate["minimum"], rate["maximum"], rate["default"]) == (1.0, 60.0, 10.0)
    horizon = schema["$defs"]["Predict"]["properties"]["horizon"]
    assert horizon["exclusiveMinimum"] == 0.0
    validator(schema, "step", "request").validate({"count": 1})
    assert not validator(schema, "step", "request").is_valid({"count": 0})


def test_the_schema_shows_no_finite_number_sentinel(schema: dict[str, Any]) -> None:
    """Finite-only numbers are checked by the daemon; the schema shows real ranges only
    (JSON carries no NaN or infinity anyway), so +-1.8e308 never appears."""
    printed = json.dumps(schema)
    assert "1.7976931348623157e+308" not in printed and "e+308" not in printed
    sim_time = schema["$defs"]["RunUntil"]["properties"]["sim_time"]
    assert sim_time["minimum"] == 0.0 and "maximum" not in sim_time
    horizon = schema["$defs"]["Predict"]["properties"]["horizon"]
    assert "maximum" not in horizon and horizon["exclusiveMinimum"] == 0.0
    rate = schema["$defs"]["StreamStates"]["properties"]["rate"]
    assert (rate["minimum"], rate["maximum"]) == (1.0, 60.0)


def test_a_names_list_declares_its_length_per_field(schema: dict[str, Any]) -> None:
    """Every names list holds 1 to MAX_BATCH names, refused before any handler with its
    "op.field" label and value; stream_states' names may be empty (every entity)."""
    with pytest.raises(InvalidArgumentError, match=r"set_states\.names must be a list of 1 "
                       r"to 100000 items, got \[\]"):
        OPERATIONS["set_states"].decode({"names": []})
    with pytest.raises(InvalidArgumentError, match=r"step\.read must be a list of 1"):
        OPERATIONS["step"].decode({"count": 1, "read": []})
    assert OPERATIONS["stream_states"].decode({"names": []}).names == []
    names = schema["$defs"]["SetStates"]["properties"]["names"]
    assert (names["minItems"], names["maxItems"]) == (1, MAX_BATCH)
    assert "minItems" not in json.dumps(schema["$defs"]["StreamStates"]["properties"]["names"])


def test_the_schema_holds_declared_replies(schema: dict[str, Any]) -> None:
    bounds = {"names": ["a"], "bounds": pack_f64(np.zeros((1, 6)))}
    validator(schema, "get_bounds", "reply").validate(as_json(bounds))
    assert not validator(schema, "get_bounds", "reply").is_valid({"names": ["a"]})
    status = schema["$defs"]["StatusReply"]
    assert sorted(status["properties"]["state"]["enum"]) == ["paused", "playing", "stopped"]


def test_a_reply_that_does_not_fit_its_declaration_is_refused() -> None:
    fits = {"names": ["a"], "bounds": pack_f64(np.zeros((1, 6)))}
    assert rp.decode_result(rp.BoundsReply, fits, exact=True).names == ["a"]
    for wrong in ({"names": ["a"]}, {**fits, "extra": 1}, {**fits, "names": "a"}):
        with pytest.raises(MalformedRequestError, match="does not fit its declaration"):
            rp.decode_result(rp.BoundsReply, wrong, exact=True)


def test_a_newer_daemons_extra_field_is_left_out_unless_exact() -> None:
    row = {"name": "w", "live": True, "engine": "mujoco", "state": "paused", "step": 1,
           "sim_time": 0.1, "entity_count": 0, "faulted": False}
    grown = {"worlds": [{**row, "colour": "red"}]}
    assert rp.decode_result(rp.WorldsReply, grown).worlds[0].name == "w"
    with pytest.raises(MalformedRequestError, match=r"\$\.worlds\[0\]\.colour not declared"):
        rp.decode_result(rp.WorldsReply, grown, exact=True)


def test_sim_status_follows_the_status_reply() -> None:
    """The SDK's SimStatus is the declared StatusReply, field for field: a field added to
    one and not the other fails here, not in a client."""
    from dataclasses import fields

    from galton.protocol import SimStatus

    assert tuple(f.name for f in fields(SimStatus)) == rp.StatusReply.__struct_fields__


@pytest.mark.parametrize("op, args, label", [
    ("create_world", {"name": ""}, "create_world.name"),
    ("fork_world", {"name": "w" * 65}, "fork_world.name"),
    ("snapshot", {"slot": "s" * 65}, "snapshot.slot"),
    ("add_camera", {"name": "c" * 65, "camera": {}}, "add_camera.name"),
])
def test_new_world_camera_and_slot_names_declare_their_length(
        schema: dict[str, Any], op: str, args: dict[str, Any], label: str) -> None:
    with pytest.raises(InvalidArgumentError,
                       match=rf"{label} must be a string of 1 to 64 characters, got"):
        OPERATIONS[op].decode(args)
    declared = schema["$defs"][OPERATIONS[op].request.__name__]["properties"]
    field = declared[label.split(".")[1]]
    shown = field if "maxLength" in field else field["anyOf"][0]
    assert (shown["minLength"], shown["maxLength"]) == (1, 64)


@pytest.mark.parametrize("properties, said", [
    ({"frcition": 0.5}, r"update\.properties takes no field 'frcition' \(did you mean "
                        r"'friction'.*it takes: mass, friction"),
    ({"mass": -2.0}, r"update\.properties\.mass must be .*, got -2\.0"),
    ({"restitution": "high"}, r"update\.properties\.restitution must be .*, got 'high'"),
    ({"rgba": [1, 0, 0]}, r"update\.properties\.rgba must be a list of 4 to 4 items"),
    ({"rgba": [1, 0, 0, 2]}, r"update\.properties\.rgba\[3\] must be float <= 1\.0, got 2"),
])
def test_update_properties_are_declared(properties: dict[str, Any], said: str) -> None:
    with pytest.raises(InvalidArgumentError, match=said):
        OPERATIONS["update"].decode({"names": ["a"], "properties": properties})


def test_a_typed_request_encodes_to_the_map_that_decodes_to_it() -> None:
    """encode_args leaves out what is None (not sent) and writes nested Structs, in maps
    and lists too, as maps: the daemon decodes the map back to the same request."""
    request = rq.Predict(horizon=1.0, read=["a"], perturb=rq.Perturb(
        position=0.01, bodies={"a": rq.Sigmas(velocity=0.2)}),
        plans=[[rq.PlanStep(at=0.5, wrenches={"names": ["a"]})]],
        score=rq.Score(body="a", target=[1.0, 2.0, 3.0]))
    args = rq.encode_args(request)
    assert args == {
        "horizon": 1.0, "read": ["a"], "first_future": 0,
        "perturb": {"position": 0.01, "orientation": 0.0, "velocity": 0.0,
                    "bodies": {"a": {"position": 0.0, "orientation": 0.0, "velocity": 0.2}}},
        "plans": [[{"at": 0.5, "wrenches": {"names": ["a"]}}]],
        "score": {"body": "a", "target": [1.0, 2.0, 3.0]}}
    assert rq.decode_args("predict", rq.Predict, args) == request


def test_one_field_is_refused_as_in_the_whole_request() -> None:
    perturb = {"bodies": {"a": {"velocity": 101}}}
    with pytest.raises(InvalidArgumentError) as alone:
        rq.decode_field("predict", rq.Predict, "perturb", perturb)
    with pytest.raises(InvalidArgumentError) as whole:
        rq.decode_args("predict", rq.Predict, {"horizon": 1.0, "perturb": perturb})
    assert str(alone.value) == str(whole.value) == (
        "predict.perturb.bodies[...].velocity must be a finite number in [0, 100], got 101")
    with pytest.raises(InvalidArgumentError, match=r"^predict\.perturb must be object, got 3$"):
        rq.decode_field("predict", rq.Predict, "perturb", 3)
    assert rq.decode_field("predict", rq.Predict, "perturb", {}) == rq.Perturb()
