"""Every reply a declared operation gives fits its declaration exactly (no field missing,
none extra), on every engine: the daemon and the SDK read one declaration. (The ``sim``
fixture holds every reply of the whole suite to its declaration too: conftest.py.)"""

from __future__ import annotations

from typing import Any

import numpy as np
from support import ball_row

from galton.client import Client
from galton.protocol import pack_f64
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
        decode_result(declared, reply.result)
