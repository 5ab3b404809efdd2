"""Every reply a declared operation gives fits its declaration exactly (no field missing,
none extra), on every engine: the daemon and the SDK read one declaration. (The ``sim``
fixture holds every reply of the whole suite to its declaration too: conftest.py.)"""

from __future__ import annotations

from typing import Any

import numpy as np
from support import ball_row

from galton.client import Client
from galton.protocol import ResultCode, pack_f64
from galton.protocol.operations import OPERATIONS
from galton.protocol.replies import decode_result


def test_real_replies_fit_their_declarations(sim: Client) -> None:
    names, group = ball_row(2)
    pose = pack_f64(np.tile([0, 0, 1, 0, 0, 0, 1.0], (1, 1)))
    calls: list[tuple[str, dict[str, Any]]] = [
        ("spawn", {"groups": [group.to_wire()]}), ("list", {}), ("get_states", {}),
        ("get_bounds", {"names": names}), ("get_shapes", {}),
        ("set_states", {"names": names[:1], "poses": pose}),
        ("update", {"names": names, "properties": {"friction": 0.5}}), ("get_params", {}),
        ("apply_wrench", {"names": names[:1], "wrenches": pack_f64(np.zeros((1, 6)))}),
        ("clear_wrenches", {}), ("delete", {"names": names[1:]}), ("status", {}),
        ("set_rtf", {"rtf": 2.0}), ("play", {}), ("pause", {}), ("reset", {"scope": "state"}),
        ("stop", {})]
    calls.append(("set_params", {"params": sim.get_params()}))
    for op, args in calls:
        declared = OPERATIONS[op].reply
        assert declared is not None, op
        reply = sim.request(op, args)
        assert reply.ok, (op, reply.message)
        decode_result(declared, reply.result, exact=True)


def test_replies_declared_later_fit_too(sim: Client) -> None:
    """The replies declared with the rest (issue 36's second round), on every engine."""
    names, group = ball_row(2, prefix="later")
    sim.request("spawn", {"groups": [group.to_wire()]})
    calls: list[tuple[str, dict[str, Any]]] = [
        ("capabilities", {}), ("step", {"count": 2, "read": names}),
        ("run_until", {"sim_time": 0.1, "read": names,
                       "until_rest": {"speed": 100.0, "every": 0.01}}),
        ("snapshot", {"slot": "later", "blob": True}), ("snapshots", {}),
        ("restore", {"slot": "later"}), ("list_worlds", {}),
        ("create_world", {"name": "later_side"}), ("delete_world", {"name": "later_side"}),
        ("delete_snapshot", {"slot": "later"}), ("contacts", {}), ("cameras", {}),
        ("predict", {"horizon": 0.01, "read": names}),
        ("compare", {"names": names[:1], "poses": pack_f64(np.tile(
            [0, 0, 1, 0, 0, 0, 1.0], (1, 1)))}),
        ("raycast", {"origins": pack_f64(np.array([[0, 0, 5.0]])),
                     "directions": pack_f64(np.array([[0, 0, -1.0]]))}),
        ("take_control", {}), ("release_control", {}), ("delete", {"names": names})]
    for op, args in calls:
        declared = OPERATIONS[op].reply
        assert declared is not None, op
        reply = sim.request(op, args)
        if reply.code == ResultCode.FEATURE_UNSUPPORTED:  # an engine's stated gap (raycast)
            continue
        assert reply.ok, (op, reply.message)
        decode_result(declared, reply.result, exact=True)
