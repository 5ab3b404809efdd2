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


def test_a_moving_body_lighter_than_the_lightest_is_refused_unless_given_a_mass(
        sim: Client) -> None:
    """A 0.5 mm sphere weighs 5e-7 kg at 1000 kg/m³: under MIN_MASS, as restore refuses it."""
    pose = pack_f64(np.array([[0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]]))
    before = sim.list()
    with pytest.raises(InvalidArgumentError, match=r"MIN_MASS") as refused:
        sim.call("spawn", {"groups": [{"shape": "sphere", "size": [0.0005], "names": ["dust"],
                                       "poses": pose}]})
    assert refused.value.details == {"field": "mass", "min": 1e-6}
    assert sim.list() == before
    sim.call("spawn", {"groups": [{"shape": "sphere", "size": [0.0005], "names": ["dust"],
                                   "poses": pose, "mass": 1e-3}]})
    sim.call("spawn", {"groups": [{"shape": "sphere", "size": [0.0005], "names": ["grain"],
                                   "poses": pose, "static": True}]})
    assert {e.name for e in sim.list()} >= {"dust", "grain"}
