"""get_entities: the entities a name regex and/or a world-frame box select (ROS 2
simulation_interfaces' GetEntities), and the typed errors of bad filters. Engine
independent: it reads the scene and get_bounds' boxes."""

from __future__ import annotations

import pytest

from galton.client import Client, spheres
from galton.protocol import InvalidArgumentError, ResultCode


def test_filters_select_by_name_and_region(sim: Client) -> None:
    sim.spawn(spheres(["ball_a", "ball_b", "crate"], [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0],
                                                      [0.0, 3.0, 1.0]], 0.25, static=True))
    assert sim.get_entities() == ["ball_a", "ball_b", "crate"]
    assert sim.get_entities(pattern="ball_*") == ["ball_a", "ball_b"]
    # ball_a's box reaches x = 0.25; ball_b's starts at 1.75: the box x <= 0.3 holds only
    # the two at x = 0, and touching edges count.
    assert sim.get_entities(region=[[-1, -1, 0], [0.3, 5, 2]]) == ["ball_a", "crate"]
    assert sim.get_entities(region=[[1.75, 0, 1], [1.75, 0, 1]]) == ["ball_b"]
    assert sim.get_entities(pattern="*a*", region=[[-1, -1, 0], [0.3, 0.3, 2]]) == ["ball_a"]
    assert sim.get_entities(pattern="nothing") == []


def test_bad_filters_are_invalid_and_named(sim: Client) -> None:
    assert sim.get_entities(pattern="(a|a)*$") == []  # a glob: no regex backtracking
    with pytest.raises(InvalidArgumentError, match=r"get_entities\.pattern"):
        sim.request("get_entities", {"pattern": 5}).raise_for_code()
    with pytest.raises(InvalidArgumentError, match=r"get_entities\.region holds 1 rows"):
        sim.get_entities(region=[0, 0, 0])
    with pytest.raises(InvalidArgumentError, match=r"min corner .* exceeds its max corner"):
        sim.get_entities(region=[[1, 0, 0], [0, 1, 1]])
    with pytest.raises(InvalidArgumentError, match="NaN or infinity"):
        sim.get_entities(region=[[0, 0, 0], [float("nan"), 1, 1]])
    reply = sim.request("get_entities", {"region": "box"})  # not a bin
    assert reply.code == ResultCode.INVALID_ARGUMENT and "get_entities.region" in reply.message
