"""The fuzzer's extreme-number cases (issue 46) on every engine: 0 daemon exits, 0 untyped
replies, 0 extremes accepted, 0 applied after a refusal, and the world still steps."""

from __future__ import annotations

import numpy as np
import pytest

from galton.client import Client
from galton.client.fuzz.extremes import run_extremes
from galton.protocol import InvalidArgumentError, pack_f64


def test_no_extreme_number_reaches_an_engine(sim: Client) -> None:
    report = run_extremes(sim)
    assert report.ok, report.to_dict()
    assert report.cases > 100 and report.codes == {"INVALID_ARGUMENT": report.cases}


def test_a_refused_quaternion_names_its_field_and_a_near_unit_one_is_normalised(
        sim: Client) -> None:
    pose = np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.5]])
    sim.call("spawn", {"groups": [{"shape": "sphere", "size": [0.05], "names": ["b"],
                                   "poses": pack_f64(pose)}]})
    assert sim.get_states(["b"]).poses[0, 6] == pytest.approx(1.0)
    pose[0, 6] = 1e155
    with pytest.raises(InvalidArgumentError, match=r"set_states\.poses row 0.*\[0\.5, 2\]"):
        sim.call("set_states", {"names": ["b"], "poses": pack_f64(pose)})
