"""Loaded models in the MuJoCo engine on its own: URDF and MJCF roots and links, their
joints as described, states of links, and how models leave the world.

URDF files come from pybullet_data, passed as text with absolute mesh paths (made so by
the daemon's own model_files, as the daemon does for the engine).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet_data
import pytest

from galton.daemon.engines.mujoco.engine import MujocoEngine
from galton.daemon.world.model_files import resolve_model
from galton.protocol import (
    BodyGroup,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NameNotUniqueError,
    NotFoundError,
)

DATA = Path(pybullet_data.getDataPath())
KUKA = "kuka_iiwa/model.urdf"
ARM = """<mujoco>
  <compiler angle="radian"/>
  <worldbody>
    <body name="base" pos="0 0 1">
      <geom type="box" size=".1 .1 .1"/>
      <body name="upper" pos="0 0 .1">
        <joint name="shoulder" type="hinge" axis="0 2 0" range="-1 1" damping="0.3"
               actuatorfrcrange="-40 40"/>
        <geom type="capsule" fromto="0 0 0 0 0 .4" size=".03"/>
        <body pos="0 0 .4">
          <joint type="slide" axis="0 0 1"/>
          <joint type="ball"/>
          <geom type="sphere" size=".05"/>
          <body name="tip"><geom type="sphere" size=".02" pos="0 0 .1"/></body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator><position joint="shoulder" kp="100"/></actuator>
</mujoco>"""


def urdf_text(relative: str) -> str:
    """The URDF as the daemon hands it over: its mesh file names absolute."""
    path = DATA / relative
    return resolve_model("urdf", path.read_text(), str(path), [])


def urdf_links(relative: str) -> list[str]:
    return [link.get("name", "") for link in ET.parse(DATA / relative).getroot().iter("link")]


@pytest.fixture
def engine() -> MujocoEngine:
    return MujocoEngine()


def test_a_fixed_urdf_is_a_static_root_and_its_links(engine: MujocoEngine) -> None:
    infos = engine.load_model("urdf", urdf_text(KUKA), None, "k/")
    assert [i.name for i in infos] == ["k/" + n for n in urdf_links(KUKA)]
    assert [(i.shape, i.static, i.model, i.source) for i in infos] == \
        [("model", True, "k/lbr_iiwa_link_0", "model")] + \
        [("link", False, "k/lbr_iiwa_link_0", "model")] * 7
    engine.step(500)
    poses, _ = engine.get_states(["k/lbr_iiwa_link_0"])
    np.testing.assert_array_equal(poses, [[0, 0, 0, 0, 0, 0, 1]])


def test_a_floating_urdf_falls_on_a_free_joint(engine: MujocoEngine) -> None:
    """(kuka_iiwa/model.urdf's base has no mass: a free joint on it is refused.)"""
    with pytest.raises(InvalidArgumentError, match="mass"):
        engine.load_model("urdf", urdf_text(KUKA), None, "k/", fixed_base=False)
    engine.load_model("urdf", urdf_text("kuka_iiwa/model_free_base.urdf"), None, "k/",
                      fixed_base=False)
    joint = engine.joints()[0]
    assert (joint.name, joint.type, joint.parent, joint.child) == (
        "k/lbr_iiwa_link_0:free", "free", "", "k/lbr_iiwa_link_0")
    engine.step(100)
    _, twists = engine.get_states(["k/lbr_iiwa_link_0"])
    assert twists[0, 2] < -1.0


def test_urdf_joints_are_described_as_in_the_file(engine: MujocoEngine) -> None:
    engine.load_model("urdf", urdf_text("r2d2.urdf"), None, "r/", fixed_base=False)
    engine.load_model("urdf", urdf_text("cartpole.urdf"), None, "c/")
    joints = {j.name: j for j in engine.joints()}
    wheel, gripper = joints["r/right_front_wheel_joint"], joints["r/gripper_extension"]
    assert (wheel.type, wheel.lower, wheel.upper, wheel.mode) == ("revolute", None, None, "none")
    assert (gripper.type, gripper.lower, gripper.upper) == ("prismatic", -0.38, 0.0)
    assert (gripper.effort_limit, gripper.velocity_limit) == (1000.0, 0.5)
    leg = joints["r/base_to_right_leg"]
    assert (leg.type, leg.parent, leg.child, leg.axis) == (
        "fixed", "r/base_link", "r/right_leg", (0.0, 0.0, 0.0))
    slider = joints["c/slider_to_cart"]
    assert (slider.type, slider.axis, slider.lower, slider.upper, slider.parent,
            slider.child) == ("prismatic", (1.0, 0.0, 0.0), -15.0, 15.0, "c/slideBar", "c/cart")
    names = urdf_links("r2d2.urdf")
    assert {j.child for j in joints.values() if j.model == "r/base_link"} == \
        {"r/" + n for n in names}


def test_a_urdf_world_link_stays_a_link(engine: MujocoEngine) -> None:
    """MuJoCo would take pendulum5's link "world" for its world body: it stays the root."""
    infos = engine.load_model("urdf", urdf_text("pendulum5.urdf"), None, "p/")
    assert [i.name for i in infos] == ["p/" + n for n in urdf_links("pendulum5.urdf")]
    assert engine.joints()[0].parent == "p/world"
    infos = engine.load_model("urdf", urdf_text("pendulum5.urdf"), None, "")
    assert [i.name for i in infos] == urdf_links("pendulum5.urdf")
    assert engine.joints()[5].parent == "world"
    engine.step(10)
    np.testing.assert_array_equal(engine.get_states(["world"])[0], [[0, 0, 0, 0, 0, 0, 1]])
    with pytest.raises(NameNotUniqueError, match="world"):
        engine.load_model("urdf", urdf_text("pendulum5.urdf"), None, "")
    engine.delete(["world"])
    engine.load_model("urdf", urdf_text("pendulum5.urdf"), None, "")


def test_panda_loads_with_its_meshes(engine: MujocoEngine) -> None:
    infos = engine.load_model("urdf", urdf_text("franka_panda/panda.urdf"), None, "")
    assert [i.name for i in infos] == urdf_links("franka_panda/panda.urdf")
    assert sum(j.type == "revolute" for j in engine.joints()) == 7


def test_mjcf_joints_get_names_and_the_files_actuators_go(engine: MujocoEngine) -> None:
    """The file's position servo would hold the shoulder: it is gone, the arm swings."""
    infos = engine.load_model("mjcf", ARM, None, "a/")
    assert [(i.name, i.shape) for i in infos] == [
        ("a/base", "model"), ("a/upper", "link"), ("a/body0", "link"), ("a/tip", "link")]
    described = [(j.name, j.type, j.parent, j.child) for j in engine.joints()]
    assert described == [
        ("a/shoulder", "revolute", "a/base", "a/upper"),
        ("a/body0:joint0", "prismatic", "a/upper", "a/body0"),
        ("a/body0:joint1", "spherical", "a/upper", "a/body0"),
        ("a/tip:fixed", "fixed", "a/body0", "a/tip")]
    shoulder = engine.joints()[0]
    assert shoulder.axis == (0.0, 1.0, 0.0)
    assert (shoulder.lower, shoulder.upper, shoulder.damping, shoulder.effort_limit) == (
        -1.0, 1.0, 0.3, 40.0)
    engine.set_joint_states(["a/shoulder"], np.array([0.5]), None)
    engine.step(200)
    assert engine.get_joint_states(["a/shoulder"])[2][0] == 0.0  # no actuator force
    assert abs(engine.get_joint_states(["a/shoulder"])[0][0] - 0.5) > 0.05


def test_link_states_are_their_frames_moving(engine: MujocoEngine) -> None:
    """A link's pose is its frame origin (not its centre of mass); its twist is that
    origin's velocity: the pose's change over a short step agrees with it."""
    engine.load_model("urdf", urdf_text(KUKA), None, "k/")
    names = [j.name for j in engine.joints()]
    engine.set_joint_states(names, np.full(7, 0.3), np.linspace(-1, 1, 7))
    links = [f"k/lbr_iiwa_link_{i}" for i in range(1, 8)]
    before, twists = engine.get_states(links)
    m, ids = engine.model, [engine.ids[n] for n in links]
    np.testing.assert_allclose(before[:, :3], engine.data.xpos[ids])
    engine.set_params({"timestep": 1e-5})
    engine.step(1)
    after, _ = engine.get_states(links)
    np.testing.assert_allclose((after[:, :3] - before[:, :3]) / 1e-5, twists[:, :3],
                               atol=1e-3)
    assert m.body_ipos[ids].any()  # the centres of mass are elsewhere


def test_link_properties_are_their_own(engine: MujocoEngine) -> None:
    engine.load_model("urdf", urdf_text("cartpole.urdf"), None, "c/")
    props = engine.properties(["c/slideBar", "c/cart", "c/pole"])
    assert math.isnan(props[0, 0])  # a fixed root has no mass
    np.testing.assert_allclose(props[1:, 0], [1.0, 0.1])
    assert np.isnan(props[:, 2]).all()


def test_deleting_a_model_takes_its_links_joints_targets_and_wrenches(
        engine: MujocoEngine) -> None:
    engine.load_model("urdf", urdf_text("cartpole.urdf"), None, "c/")
    engine.load_model("urdf", urdf_text("cartpole.urdf"), None, "d/")
    one = np.ones(1)
    engine.set_joint_targets(["c/cart_to_pole"], "effort", one, one, one, np.full(1, np.inf))
    engine.set_wrenches(["c/pole"], np.ones((1, 6)), None)
    with pytest.raises(InvalidArgumentError, match="link"):
        engine.delete(["c/pole"])
    engine.delete(["c/slideBar"])
    assert {j.model for j in engine.joints()} == {"d/slideBar"}
    assert not engine.wrenches.held and not engine.loaded_joints.targets
    assert not engine.data.xfrc_applied.any()
    with pytest.raises(NotFoundError):
        engine.get_states(["c/pole"])
    with pytest.raises(NotFoundError):
        engine.get_joint_states(["c/cart_to_pole"])
    engine.load_model("urdf", urdf_text("cartpole.urdf"), None, "c/")  # the names are free
    engine.clear()
    assert engine.joints() == [] and engine.model.nu == 0


def test_joint_names_that_are_not_one_dof_or_unknown_are_refused(engine: MujocoEngine) -> None:
    engine.load_model("mjcf", ARM, None, "a/")
    with pytest.raises(InvalidArgumentError, match="degree of freedom"):
        engine.get_joint_states(["a/body0:joint1"])
    with pytest.raises(NotFoundError, match="nope"):
        engine.set_joint_states(["nope"], np.zeros(1), None)


@pytest.mark.parametrize("text", ["<robot name='r'><link name='a'>", "<sdf/>",
                                  "<robot name='r'><link name='a'><visual><geometry><mesh "
                                  "filename='/no/such.stl'/></geometry></visual></link>"
                                  "</robot>"])
def test_a_broken_urdf_is_refused_and_changes_nothing(engine: MujocoEngine, text: str) -> None:
    engine.spawn([BodyGroup(shape="sphere", size=(0.1,), names=["b"],
                            poses=np.array([[0, 0, 1, 0, 0, 0, 1.0]]))])
    spec = engine.mj_spec.to_xml()
    with pytest.raises(InvalidArgumentError, match="URDF"):
        engine.load_model("urdf", text, None, "x/")
    assert engine.mj_spec.to_xml() == spec and list(engine.entities) == ["b"]
    with pytest.raises(FeatureUnsupportedError):
        engine.load_model("sdf", text, None, "x/")


def test_a_urdf_loads_from_a_path_with_relative_meshes(engine: MujocoEngine) -> None:
    infos = engine.load_model("urdf", None, str(DATA / KUKA), "k/")
    assert len(infos) == 8


def test_a_deleted_models_meshes_go_with_it(engine: MujocoEngine) -> None:
    """Else the same model reloaded under the same prefix would repeat their names."""
    for _ in range(2):
        engine.load_model("urdf", urdf_text(KUKA), None, "")
        engine.delete(["lbr_iiwa_link_0"])
    assert not engine.mj_spec.meshes


def test_a_load_refused_at_its_recompile_leaves_no_meshes(
        engine: MujocoEngine, monkeypatch: pytest.MonkeyPatch) -> None:
    """A refusal after the attach (the world's recompile, forced to fail here as MuJoCo
    fails when out of memory) takes the model's assets out with its bodies."""
    engine.load_model("urdf", urdf_text(KUKA), None, "a/")
    meshes = len(engine.mj_spec.meshes)

    def refuse(*_: object) -> None:
        raise InvalidArgumentError("refused")

    monkeypatch.setattr(MujocoEngine, "recompile", refuse)
    with pytest.raises(InvalidArgumentError, match="refused"):
        engine.load_model("urdf", urdf_text(KUKA), None, "b/")
    assert len(engine.mj_spec.meshes) == meshes and "b/lbr_iiwa_link_0" not in engine.entities
