"""Loaded models through a real daemon, the same on every engine: robots by path and by text,
their links and joints as the file declares them (and alike on both engines), MJCF models,
floating bases, and a model moving, going and coming back whole."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from support.daemons import start_daemon
from support.models import (
    KUKA_JOINTS,
    ROBOTS,
    Pendulum,
    apply_wrench,
    free_box_urdf,
    get_joint_states,
    joints,
    load,
    load_robot,
    model_snapshot,
    set_joint_states,
    set_targets,
    step_joints,
    urdf_joints,
    urdf_links,
)

from galton.client import Client, EmbeddedDaemon
from galton.protocol import (
    FeatureUnsupportedError,
    InvalidArgumentError,
    JointInfo,
    NotFoundError,
)


@pytest.mark.parametrize("robot", list(ROBOTS))
def test_a_robot_loads_by_path_with_every_link(sim: Client, robot: str) -> None:
    path = ROBOTS[robot]
    names = load(sim, "urdf", path=path)
    declared = urdf_links(path)
    assert sorted(names) == sorted(declared)
    root = names[0]
    entities = {e.name: e for e in sim.list()}
    assert set(entities) == set(declared)
    assert (entities[root].shape, entities[root].static) == ("model", True)
    assert {e.model for e in entities.values()} == {root}
    assert {e.source for e in entities.values()} == {"model"}
    assert {entities[n].shape for n in names[1:]} <= {"link"}
    assert sim.get_states(names).poses.shape == (len(names), 7)



@pytest.mark.parametrize("robot", list(ROBOTS))
def test_joints_are_those_the_file_declares(sim: Client, robot: str) -> None:
    path = ROBOTS[robot]
    [root, *_] = load_robot(sim, robot)
    listed = {j.name: j for j in joints(sim)}
    declared = urdf_joints(path)
    assert sorted(listed) == sorted(d.name for d in declared)
    for want in declared:
        got = listed[want.name]
        assert (got.model, got.type, got.parent, got.child, got.mode) == (
            root, want.type, want.parent, want.child, "none"), want.name
        np.testing.assert_allclose(got.axis, want.axis, atol=1e-9, err_msg=want.name)
        assert (got.lower, got.upper) == pytest.approx((want.lower, want.upper)), want.name
        assert got.damping == pytest.approx(want.damping), want.name



@pytest.mark.parametrize("robot", list(ROBOTS))
def test_both_engines_list_the_same_joints(daemons: dict[str, EmbeddedDaemon],
                                           robot: str) -> None:
    (mj_joints, mj_links), (pb_joints, pb_links) = (
        _joints_and_links(start_daemon(daemons, engine), robot)
        for engine in ("mujoco", "pybullet"))
    assert mj_links == pb_links
    assert mj_joints.keys() == pb_joints.keys()
    differ = {name: (mj_joints[name], pb_joints[name]) for name in mj_joints
              if mj_joints[name] != pb_joints[name]}
    assert not differ, f"(mujoco, pybullet) differ: {differ}"



def _joints_and_links(daemon: EmbeddedDaemon, robot: str
                      ) -> tuple[dict[str, JointInfo], list[tuple[object, ...]]]:
    with Client(daemon.instance, daemon.endpoint, timeout=20.0) as client:
        client.load_world(daemon.engine)
        load_robot(client, robot)
        return ({j.name: j for j in joints(client)},
                sorted((e.name, e.shape, e.model, e.static) for e in client.list()))



def test_an_mjcf_model_has_links_and_joints(sim: Client) -> None:
    names = load(sim, "mjcf", text=Pendulum().mjcf(), prefix="p/")
    assert names == ["p/base", "p/bob"]
    shapes = {e.name: (e.shape, e.model) for e in sim.list()}
    assert shapes == {"p/base": ("model", "p/base"), "p/bob": ("link", "p/base")}
    [hinge] = joints(sim)
    assert (hinge.name, hinge.model, hinge.type, hinge.parent, hinge.child) == (
        "p/hinge", "p/base", "revolute", "p/base", "p/bob")
    assert hinge.axis == pytest.approx((0, 1, 0))
    assert joints(sim, model="p/base") == [hinge]
    assert joints(sim, names=["p/hinge"]) == [hinge]



def test_a_prefix_names_links_and_joints(sim: Client) -> None:
    load_robot(sim, "kuka", "a/")
    load_robot(sim, "kuka", "b/")
    names = [j.name for j in joints(sim, model="b/lbr_iiwa_link_0")]
    assert names == [f"b/{n}" for n in KUKA_JOINTS]
    assert {j.parent.split("/")[0] for j in joints(sim, model="a/lbr_iiwa_link_0")} == {"a"}



def test_a_link_alone_is_refused_and_nothing_changes(sim: Client) -> None:
    load_robot(sim, "kuka")
    link = "lbr_iiwa_link_3"
    before = model_snapshot(sim)
    with pytest.raises(InvalidArgumentError, match="lbr_iiwa_link_0"):
        sim.set_states([link], poses=np.array([[0, 0, 1, 0, 0, 0, 1.0]]))
    with pytest.raises(InvalidArgumentError, match="lbr_iiwa_link_0"):
        sim.update([link], friction=0.3)
    with pytest.raises(InvalidArgumentError, match="lbr_iiwa_link_0"):
        sim.delete([link])
    model_snapshot(sim).assert_same(before)



def test_deleting_a_root_removes_its_links_and_joints(sim: Client) -> None:
    load_robot(sim, "kuka")
    load(sim, "urdf", text=Pendulum().urdf(), prefix="p/")
    sim.delete(["lbr_iiwa_link_0"])
    assert sorted(e.name for e in sim.list()) == ["p/base", "p/bob"]
    assert [j.name for j in joints(sim)] == ["p/hinge"]
    with pytest.raises(NotFoundError):
        get_joint_states(sim, KUKA_JOINTS[:1])
    step_joints(sim, 10, ["p/hinge"])  # the rest still steps



def test_a_missing_mesh_is_invalid_naming_it(sim: Client, tmp_path: Path) -> None:
    load(sim, "urdf", text=Pendulum().urdf(), prefix="p/")
    before = model_snapshot(sim)
    missing = tmp_path / "meshes" / "nowhere.stl"
    text = ROBOTS["kuka"].read_text().replace("meshes/link_3.stl", str(missing))
    with pytest.raises(InvalidArgumentError, match=r"nowhere\.stl") as error:
        load(sim, "urdf", text=text, search_path=str(ROBOTS["kuka"].parent))
    assert "nowhere.stl" in str(error.value.details.get("missing_file"))
    model_snapshot(sim).assert_same(before)



@pytest.mark.parametrize("fmt", ["urdf", "mjcf"])
def test_a_model_without_collision_geometry_loads(sim: Client, fmt: str) -> None:
    pendulum = Pendulum(geom=False)
    load(sim, fmt, text=pendulum.urdf() if fmt == "urdf" else pendulum.mjcf())
    set_joint_states(sim, ["hinge"], 0.3)
    assert step_joints(sim, 10, ["hinge"]).positions[0] < 0.3



def test_a_floating_base_has_a_free_joint(sim: Client) -> None:
    names = load(sim, "urdf", text=free_box_urdf(2.0), prefix="f/", fixed_base=False)
    assert names == ["f/crate"]
    [info] = sim.list()
    assert (info.shape, info.static, info.model) == ("model", False, "f/crate")
    [free] = joints(sim)
    assert (free.name, free.type, free.parent, free.child) == (
        "f/crate:free", "free", "", "f/crate")
    assert free.axis == (0.0, 0.0, 0.0)
    with pytest.raises(InvalidArgumentError, match="get_states"):
        get_joint_states(sim, ["f/crate:free"])
    sim.step(20)
    assert sim.get_states(names).positions[0, 2] < 0  # it falls



def test_a_root_teleport_carries_its_links(sim: Client) -> None:
    load_robot(sim, "kuka")
    set_joint_states(sim, KUKA_JOINTS, 0.3)
    links = [e.name for e in sim.list()]
    before = sim.get_states(links).poses
    moved = before[0].copy()
    moved[:3] += [1.0, -2.0, 0.5]
    sim.set_states(links[:1], poses=moved[None])
    after = sim.get_states(links).poses
    np.testing.assert_allclose(after[:, :3] - before[:, :3], [[1.0, -2.0, 0.5]] * len(links),
                               atol=1e-6)  # PyBullet's link frames are float32
    np.testing.assert_allclose(get_joint_states(sim, KUKA_JOINTS).positions, 0.3, atol=1e-12)



def test_a_reloaded_model_holds_no_old_target_or_wrench(sim: Client) -> None:
    load_robot(sim, "kuka")
    set_targets(sim, KUKA_JOINTS, "effort", 5.0)
    apply_wrench(sim, ["lbr_iiwa_link_7"], [[0, 0, 50, 0, 0, 0]])
    sim.delete(["lbr_iiwa_link_0"])
    load_robot(sim, "kuka")
    assert {j.mode for j in joints(sim)} == {"none"}
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    read = step_joints(sim, 20, KUKA_JOINTS)
    np.testing.assert_array_equal(read.efforts, 0.0)
    np.testing.assert_allclose(read.positions, 0.0, atol=1e-12)  # nothing pushes it



def test_each_top_level_mjcf_body_is_a_model_with_its_joints(sim: Client) -> None:
    text = Pendulum().mjcf().replace("</worldbody>", """<body name="arm" pos="1 0 2">
      <body name="hand"><joint name="wrist" type="slide" axis="1 0 0" range="-0.1 0.1"
          limited="true"/><geom type="sphere" size="0.05" mass="0.5"/></body></body>
      </worldbody>""")
    names = load(sim, "mjcf", text=text, prefix="m/")
    assert sorted(names) == ["m/arm", "m/base", "m/bob", "m/hand"]
    models = {e.name: e.model for e in sim.list()}
    assert models == {"m/base": "m/base", "m/bob": "m/base", "m/arm": "m/arm",
                      "m/hand": "m/arm"}
    wrist = joints(sim, model="m/arm")
    assert [(j.name, j.type, j.parent, j.child) for j in wrist] == [
        ("m/wrist", "prismatic", "m/arm", "m/hand")]
    assert (wrist[0].lower, wrist[0].upper) == pytest.approx((-0.1, 0.1))
    sim.delete(["m/base"])
    assert [j.name for j in joints(sim)] == ["m/wrist"]



# A stand welded to the world (no joint), an arm on a damped hinge, a puck whose density
# comes from a default class: what the file says, every engine must say.
STAND_MJCF = """<mujoco><default><geom density="500"/></default><worldbody>
  <body name="stand" pos="0 0 1"><geom type="box" size="0.1 0.1 0.1" mass="1.8"/>
    <body name="arm" pos="0.2 0 0"><joint name="hinge" axis="0 0 1" damping="0.1"/>
      <geom type="sphere" size="0.05" mass="1" pos="0.2 0 0"/></body></body>
  <body name="puck" pos="2 0 1"><freejoint/><geom type="cylinder" size="0.1 0.05"/></body>
</worldbody></mujoco>"""
ARM_INERTIA = 1.0 * (0.4 * 0.05**2 + 0.2**2)  # kg m² about the hinge


def test_an_mjcf_file_says_the_same_on_every_engine(sim: Client) -> None:
    """Masses, the inertia MuJoCo infers from the geoms (the damped swing's decay is
    damping over that inertia) and the damping itself, on every engine."""
    load(sim, "mjcf", text=STAND_MJCF)
    listed = {e.name: e for e in sim.list()}
    assert (listed["stand"].shape, listed["stand"].static) == ("model", True)
    assert listed["arm"].mass == pytest.approx(1.0)
    assert listed["puck"].mass == pytest.approx(500 * np.pi * 0.1**2 * 0.1)
    [hinge] = joints(sim, names=["hinge"])
    assert hinge.damping == pytest.approx(0.1)
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    set_joint_states(sim, ["hinge"], 0.0, velocities=2.0)
    stand = sim.get_states(["stand"]).poses
    steps = round(0.2 / sim.status().timestep)
    read = step_joints(sim, steps, ["hinge"])
    decay = np.exp(-0.1 * steps * sim.status().timestep / ARM_INERTIA)
    assert read.velocities[0] == pytest.approx(2.0 * decay, rel=0.03)
    np.testing.assert_array_equal(sim.get_states(["stand"]).poses, stand)


def test_a_ball_joint_loads_or_is_refused_naming_it(sim: Client, engine: str) -> None:
    text = STAND_MJCF.replace('<joint name="hinge" axis="0 0 1"', '<joint name="shoulder" '
                              'type="ball"')
    if engine == "pybullet":
        with pytest.raises(FeatureUnsupportedError, match=r"ball joint.*shoulder"):
            load(sim, "mjcf", text=text)
        assert sim.list() == []
        return
    load(sim, "mjcf", text=text)
    [shoulder] = joints(sim, names=["shoulder"])
    assert (shoulder.type, shoulder.child) == ("spherical", "arm")
