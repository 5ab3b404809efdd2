"""Model loading, engine switching and capability honesty, through a real daemon."""

from __future__ import annotations

import pytest
from support import ball_row

from galton.client import Client
from galton.protocol import FeatureUnsupportedError, InvalidArgumentError

MJCF = """<mujoco><worldbody>
  <body name="box" pos="0 0 1"><freejoint/><geom type="box" size="0.1 0.1 0.1"/></body>
  <body name="ball" pos="1 0 1"><freejoint/><geom type="sphere" size="0.05"/></body>
</worldbody></mujoco>"""

URDF = """<robot name="crate"><link name="base">
  <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
  </inertial>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
</link></robot>"""


def test_load_mjcf_makes_entities_that_fall(sim: Client) -> None:
    names = sim.load_model("mjcf", text=MJCF, prefix="m_")
    assert len(names) == 2 and all(n.startswith("m_") for n in names)
    assert {e.source for e in sim.list(name="m_*")} == {"model"}
    before = sim.get_states(names).positions[:, 2]
    sim.step(50)
    assert (sim.get_states(names).positions[:, 2] < before).all()
    sim.delete(names)
    assert sim.list() == []


def test_load_urdf_where_supported(sim: Client) -> None:
    if "urdf" not in sim.capabilities().model_formats:
        with pytest.raises(FeatureUnsupportedError, match="urdf"):
            sim.load_model("urdf", text=URDF)
        return
    [name] = sim.load_model("urdf", text=URDF, prefix="u_")
    assert name.startswith("u_") and sim.get_states([name]).poses.shape == (1, 7)


def test_a_broken_model_is_invalid_and_changes_nothing(sim: Client) -> None:
    sim.spawn(ball_row(1)[1])
    with pytest.raises(InvalidArgumentError):
        sim.load_model("mjcf", text="<mujoco><worldbody><body name='x'>")
    assert [e.name for e in sim.list()] == ["ball_0"]


def test_load_needs_text_or_path(sim: Client) -> None:
    with pytest.raises(InvalidArgumentError, match="exactly one"):
        sim.call("load_model", {"format": "mjcf"})


@pytest.mark.parametrize("target", ["mujoco", "pybullet"])
def test_load_world_switches_engine_without_restart(sim: Client, engine: str,
                                                    target: str) -> None:
    sim.spawn(ball_row(2)[1])
    status = sim.load_world(target, {"timestep": 0.004})
    assert (status.engine, status.entity_count, status.state) == (target, 0, "stopped")
    assert sim.capabilities().engine == target
    assert sim.get_params()["timestep"] == 0.004
    assert sim.step(10).step == 10
    sim.load_world(engine)


def test_load_world_with_bad_params_keeps_the_old_world(sim: Client, engine: str) -> None:
    sim.spawn(ball_row(1)[1])
    with pytest.raises(InvalidArgumentError):
        sim.load_world(engine, {"timestep": -1})
    assert [e.name for e in sim.list()] == ["ball_0"]


def test_params_have_defaults_units_docs_and_sources(sim: Client) -> None:
    caps = sim.capabilities()
    current = sim.get_params()
    assert set(current) == set(caps.params)
    for name, spec in caps.params.items():
        assert {"default", "unit", "doc", "source"} <= set(spec) and spec["doc"], name
        assert spec["source"], name
        assert current[name] == spec["default"], name  # a fresh world starts at them
    for shared in ("timestep", "gravity", "solver_iterations", "default_friction",
                   "default_restitution"):
        assert shared in caps.params
    assert {"mujoco", "pybullet"} <= set(caps.engines_available)
