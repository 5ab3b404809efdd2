"""The wire protocol on its own: envelope, arrays, records, error mapping."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest

from galton.protocol import (
    BodyGroup,
    InvalidArgumentError,
    Keys,
    MalformedRequestError,
    Reply,
    ResultCode,
    UnsupportedVersionError,
    decode_reply,
    decode_request,
    encode_reply,
    encode_request,
    error_for_code,
    pack_f64,
    unpack_f64,
)
from galton.protocol.errors import RemoteError, did_you_mean


def test_request_round_trip() -> None:
    request = decode_request(encode_request("step", {"count": 5}), "step")
    assert (request.op, request.args, request.version) == ("step", {"count": 5}, 1)


@pytest.mark.parametrize("payload, error", [
    (b"\xc1", MalformedRequestError),
    (msgpack.packb([1, 2]), MalformedRequestError),
    (msgpack.packb({"v": 99, "op": "step"}), UnsupportedVersionError),
    (msgpack.packb({"v": 1, "op": 3}), MalformedRequestError),
    (msgpack.packb({"v": 1, "op": "step", "args": [1]}), MalformedRequestError),
    (msgpack.packb({"v": 1, "op": "pause"}), MalformedRequestError),
])
def test_bad_envelopes_are_typed(payload: bytes, error: type[Exception]) -> None:
    with pytest.raises(error):
        decode_request(payload, "step")


def test_reply_round_trip_and_error_mapping() -> None:
    reply = decode_reply(encode_reply(Reply(ResultCode.NOT_FOUND, "no entity 'x'", step=3,
                                            sim_time=0.006)))
    assert reply.code == ResultCode.NOT_FOUND and reply.step == 3
    with pytest.raises(RemoteError) as caught:
        reply.raise_for_code()
    assert caught.value.code == ResultCode.NOT_FOUND


def test_every_failure_code_maps_to_its_own_class() -> None:
    classes = {type(error_for_code(code, "")) for code in ResultCode if code != ResultCode.OK}
    assert len(classes) == len(ResultCode) - 1
    for code in ResultCode:
        if code != ResultCode.OK:
            assert error_for_code(code, "m").code == code


def test_arrays_are_little_endian_rows() -> None:
    rows = np.arange(14, dtype=float).reshape(2, 7)
    data = pack_f64(rows)
    assert data[:8] == np.float64(0).astype("<f8").tobytes() and len(data) == 112
    assert np.array_equal(unpack_f64(data, 7), rows)
    with pytest.raises(InvalidArgumentError, match="whole number"):
        unpack_f64(data[:-8], 7)


def _group(**overrides: object) -> dict:
    poses = np.zeros((1, 7))
    poses[0, 6] = 1.0
    wire = BodyGroup("sphere", (0.1,), ["a"], poses).to_wire()
    wire.update(overrides)
    return wire


@pytest.mark.parametrize("overrides, message", [
    ({"shape": "cone"}, "not one of"),
    ({"size": [0.1, 0.2]}, "must hold 1"),
    ({"size": [-1.0]}, "finite number"),
    ({"names": []}, "at least one"),
    ({"names": ["a", "a"]}, "more than once"),
    ({"poses": pack_f64(np.array([[math.nan, 0, 0, 0, 0, 0, 1]]))}, "NaN"),
    ({"poses": pack_f64(np.zeros((1, 7)))}, "zero quaternion"),
    ({"poses": "text"}, "must be bytes"),
    ({"mass": -1.0}, "finite number"),
    ({"restitution": 2.0}, "finite number"),
    ({"shape": "plane", "size": [1.0, 1.0]}, "must be static"),
    ({"static": "yes"}, "must be bool"),
])
def test_body_group_validation(overrides: dict, message: str) -> None:
    with pytest.raises(InvalidArgumentError, match=message):
        BodyGroup.from_wire(_group(**overrides))


def test_body_group_normalises_quaternions() -> None:
    group = BodyGroup.from_wire(_group(poses=pack_f64(np.array([[0, 0, 1, 0, 0, 0, 2.0]]))))
    assert group.poses[0, 6] == 1.0


def test_keys_put_control_under_an_at_chunk() -> None:
    keys = Keys("robot-1")
    assert keys.control("step") == "galton/robot-1/@ctl/step"
    assert keys.alive == "galton/robot-1/alive"
    with pytest.raises(InvalidArgumentError):
        Keys("a/b")


def test_did_you_mean() -> None:
    assert "'spawn'" in did_you_mean("spwan", ["spawn", "delete"])
    assert did_you_mean("zzz", ["spawn"]) == ""


def test_replies_of_a_newer_daemon_with_extra_fields_still_parse() -> None:
    """A daemon that grew a field (as status grew controller) is read by an older client."""
    from galton.protocol import Capabilities, SimStatus, Telemetry

    status = {"state": "paused", "step": 3, "sim_time": 0.03, "timestep": 0.01,
              "target_rtf": 1.0, "rtf": 0.0, "entity_count": 0, "engine": "mujoco",
              "instance": "i", "world": "default", "faulted": False, "from_the_future": 1}
    assert SimStatus.from_wire(status).step == 3
    sample = {**{k: v for k, v in status.items() if k not in ("faulted", "controller")},
              "seq": 1, "wall_time": 0.0, "cpu_percent": 0.0, "rss_bytes": 1,
              "peak_rss_bytes": 1}
    assert Telemetry.from_wire(sample).seq == 1
    caps = {"engine": "mujoco", "engine_version": "x", "protocol_version": 1,
            "body_shapes": [], "model_formats": [], "features": [], "new_thing": {}}
    assert Capabilities.from_wire(caps).engine == "mujoco"


def test_an_instance_name_ending_in_a_line_break_is_refused() -> None:
    """``$`` matches before a final newline: the name is matched whole, so a key chunk
    never carries one."""
    from galton.protocol import InvalidArgumentError, validate_instance_name

    assert validate_instance_name("robot-1") == "robot-1"
    with pytest.raises(InvalidArgumentError):
        validate_instance_name("robot-1\n")
