"""A re-sealed snapshot's numbers obey the bounds a request's do, on every engine (issue 46):
a body of 1e-300 kg under a wrench (it aborted a DART daemon at its next step), a negative
mass, a NaN restitution, a huge quaternion, an unknown target mode, edited into the
registry or into the engine's own part of the blob, are refused with INVALID_ARGUMENT
naming the field, the world untouched, and the daemon goes on serving."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from support import snapshot

from galton.client import Client, plane, spheres
from galton.client.fuzz.snapshots import open_blob, reseal
from galton.protocol import InvalidArgumentError

Edit = Callable[[dict[str, Any], str], None]


def _scene(sim: Client) -> dict[str, Any]:
    """A ball of a given mass held under a wrench (the case that aborted DART)."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05, mass=0.5, restitution=0.6))
    sim.apply_wrench(["ball"], [[2.0, 0, 0, 0, 0, 0.1]])
    sim.step(3)
    return open_blob(bytes(sim.call("snapshot", {"blob": True})["blob"]))


def _packed(record: dict[str, Any], index: int, value: float) -> None:
    """Set one number of an array the engine packed as dtype, shape and bytes."""
    array = np.frombuffer(record["data"], dtype=record["dtype"]).copy()
    array[index] = value
    record["data"] = array.tobytes()


def _engine_body(body: dict[str, Any], key: str, value: float) -> None:
    """Set the ball's ``key`` (mass or restitution) in the engine's own format."""
    state = body["engine_state"]
    engine = state["engine"]
    if engine == "dart":
        next(i for i in state["items"] if i.get("name") == "ball")[key] = value
    elif engine == "ode":
        next(b for b in state["bodies"] if b["name"] == "ball")[key] = value
    elif engine == "pybullet":
        run = next(r for r in state["runs"] if "ball" in r.get("names", []))
        _packed(run[key], run["names"].index("ball"), value)
    elif key == "mass":  # mujoco: the compiled model's own array
        _packed(state["model"]["arrays"]["body_mass"], state["bodies"].index("ball"), value)
    else:
        next(e for e in state["entities"] if e["name"] == "ball")[key] = value


def _registry_entity(body: dict[str, Any], key: str, value: Any) -> None:
    next(e for e in body["entities"] if e["name"] == "ball")[key] = value


def _initial_quaternion(body: dict[str, Any], _: str) -> None:
    poses = np.frombuffer(body["initial_poses"], dtype="<f8").reshape(-1, 7).copy()
    poses[-1, 3:7] = (0.0, 1e308, 0.0, 1.0)
    body["initial_poses"] = poses.tobytes()


HOSTILE: dict[str, tuple[Edit, str]] = {
    "engine mass 1e-300": (lambda b, _: _engine_body(b, "mass", 1e-300), "mass"),
    "engine mass negative": (lambda b, _: _engine_body(b, "mass", -1.0), "mass"),
    "engine restitution NaN": (lambda b, _: _engine_body(b, "restitution", float("nan")),
                               "restitution|surface value"),
    "registry mass 1e-300": (lambda b, _: _registry_entity(b, "mass", 1e-300), "mass"),
    "registry friction 1e6": (lambda b, _: _registry_entity(b, "friction", 1e6), "friction"),
    "registry restitution NaN": (lambda b, _: _registry_entity(b, "restitution",
                                                               float("nan")), "restitution"),
    "registry name no string": (lambda b, _: _registry_entity(b, "name", 7), "name"),
    "initial quaternion 1e308": (_initial_quaternion, "quaternion"),
    "target mode spin": (lambda b, _: b["joint_modes"].update(r_hinge="spin"), "mode"),
    "wrench end no step": (lambda b, _: b["wrench_ends"].update(ball=-3), "step"),
    "clock base_dt NaN": (lambda b, _: b["clock"].update(base_dt=float("nan")), "base_dt"),
}


@pytest.mark.parametrize("label", list(HOSTILE))
def test_a_resealed_value_beyond_the_bounds_is_refused_and_changes_nothing(
        sim: Client, engine: str, label: str) -> None:
    body = _scene(sim)
    edit, field = HOSTILE[label]
    edit(body, engine)
    before = snapshot(sim)
    with pytest.raises(InvalidArgumentError, match=field):
        sim.call("restore", {"blob": reseal(body)})
    snapshot(sim).assert_same(before)
    sim.step(5)  # the daemon goes on serving, the world stepping as before
    assert sim.status().step == before.step + 5
