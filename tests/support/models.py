"""Helpers for joint tests: model files and texts of known physics, what a URDF declares,
and the joint operations spoken in the raw protocol (``Client.call``), so these tests do
not depend on SDK methods."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data

from galton.client import Client
from galton.protocol import JointInfo, pack_f64, unpack_f64
from support import Snapshot, snapshot

DATA = Path(pybullet_data.getDataPath())
ROBOTS = {
    "kuka": DATA / "kuka_iiwa" / "model.urdf",
    "pendulum5": DATA / "pendulum5.urdf",
    "cartpole": DATA / "cartpole.urdf",
    "r2d2": DATA / "r2d2.urdf",
    "panda": DATA / "franka_panda" / "panda.urdf",  # package:// meshes
}
KUKA_JOINTS = [f"lbr_iiwa_joint_{i}" for i in range(1, 8)]
# Position gains within what an explicit PD law allows at a 2 ms step: kd dt / I < 2 for
# link 7's 0.001 kg·m² (stiffer ones diverge on MuJoCo and swing wildly on PyBullet).
KUKA_KP = np.array([1000.0, 1500.0, 600.0, 600.0, 150.0, 60.0, 20.0])
KUKA_KD = np.array([20.0, 30.0, 10.0, 10.0, 2.0, 1.0, 0.2])
G = 9.81


# -- what a URDF declares --------------------------------------------------------------
@dataclass(frozen=True)
class DeclaredJoint:
    """A joint as the URDF file states it, in the terms of JointInfo."""

    name: str
    type: str
    parent: str
    child: str
    axis: tuple[float, float, float]
    lower: float | None
    upper: float | None
    damping: float


def urdf_joints(path: Path) -> list[DeclaredJoint]:
    """Every joint of a URDF file, in file order (continuous: revolute without limits)."""
    return [_declared(j) for j in ET.parse(path).getroot().iter("joint")]


def _declared(joint: ET.Element) -> DeclaredJoint:
    kind = joint.attrib["type"]
    limit, dynamics = joint.find("limit"), joint.find("dynamics")
    limited = kind in ("revolute", "prismatic") and limit is not None
    axis = (0.0, 0.0, 0.0)
    if kind in ("revolute", "continuous", "prismatic"):
        raw = np.array(_floats(joint.find("axis"), "xyz", "1 0 0"))
        axis = tuple(float(v) for v in raw / np.linalg.norm(raw))  # type: ignore[assignment]
    return DeclaredJoint(
        name=joint.attrib["name"], type="revolute" if kind == "continuous" else kind,
        parent=_attr(joint, "parent", "link"), child=_attr(joint, "child", "link"), axis=axis,
        lower=float(limit.attrib.get("lower", 0)) if limited and limit is not None else None,
        upper=float(limit.attrib.get("upper", 0)) if limited and limit is not None else None,
        damping=float(dynamics.attrib.get("damping", 0)) if dynamics is not None else 0.0)


def _attr(element: ET.Element, tag: str, key: str) -> str:
    found = element.find(tag)
    assert found is not None, f"<{element.tag}> has no <{tag}>"
    return found.attrib[key]


def _floats(element: ET.Element | None, key: str, default: str) -> list[float]:
    text = default if element is None else element.attrib.get(key, default)
    return [float(v) for v in text.split()]


def urdf_links(path: Path) -> list[str]:
    return [link.attrib["name"] for link in ET.parse(path).getroot().iter("link")]


# -- models of known physics -----------------------------------------------------------
@dataclass(frozen=True)
class Pendulum:
    """A point-like bob of mass ``mass`` at ``length`` below a revolute joint about y,
    with its own inertia ``bob_inertia`` about its centre (kg·m²): I = Ic + m d²."""

    mass: float = 1.0
    length: float = 0.5
    bob_inertia: float = 0.01
    lower: float | None = None
    upper: float | None = None
    damping: float = 0.0
    height: float = 2.0  # of the pivot above the origin
    geom: bool = True  # a small sphere at the bob, of no mass (the inertial is as given)

    @property
    def pivot_inertia(self) -> float:
        return self.bob_inertia + self.mass * self.length**2

    @property
    def period(self) -> float:
        """The small-angle period 2π√(I/(m g d))."""
        return 2 * math.pi * math.sqrt(self.pivot_inertia / (self.mass * G * self.length))

    @property
    def gravity_torque(self) -> float:
        """m g d: the effort that holds the link horizontal."""
        return self.mass * G * self.length

    def urdf(self) -> str:
        kind = "continuous" if self.lower is None else "revolute"
        limit = ("" if self.lower is None else
                 f'<limit lower="{self.lower}" upper="{self.upper}" effort="1000" '
                 'velocity="100"/>')
        i = self.bob_inertia
        return f"""<robot name="pendulum">
  <link name="base"><inertial><mass value="1"/>
    <inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="bob"><inertial><origin xyz="0 0 {-self.length}"/><mass value="{self.mass}"/>
    <inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>
    {self._urdf_geom()}</link>
  <joint name="hinge" type="{kind}"><parent link="base"/><child link="bob"/>
    <origin xyz="0 0 {self.height}"/><axis xyz="0 1 0"/>{limit}
    <dynamics damping="{self.damping}"/></joint>
</robot>"""

    def _urdf_geom(self) -> str:
        if not self.geom:
            return ""
        return (f'<collision><origin xyz="0 0 {-self.length}"/><geometry>'
                '<sphere radius="0.02"/></geometry></collision>')

    def _mjcf_geom(self) -> str:
        if not self.geom:
            return ""
        return f'<geom type="sphere" size="0.02" pos="0 0 {-self.length}" mass="0"/>'

    def mjcf(self) -> str:
        limit = ("" if self.lower is None else
                 f' limited="true" range="{self.lower} {self.upper}"')
        i = self.bob_inertia
        return f"""<mujoco><compiler angle="radian"/><worldbody>
  <body name="base" pos="0 0 {self.height}">
    <body name="bob"><joint name="hinge" type="hinge" axis="0 1 0"
        damping="{self.damping}"{limit}/>
      <inertial pos="0 0 {-self.length}" mass="{self.mass}" diaginertia="{i} {i} {i}"/>
      {self._mjcf_geom()}
    </body>
  </body>
</worldbody></mujoco>"""


def free_box_urdf(mass: float) -> str:
    """One cube 0.2 m wide of ``mass`` kg (a floating base when loaded with fixed_base
    False)."""
    i = mass * (0.2**2 + 0.2**2) / 12
    return f"""<robot name="crate"><link name="crate">
  <inertial><mass value="{mass}"/>
    <inertia ixx="{i}" iyy="{i}" izz="{i}" ixy="0" ixz="0" iyz="0"/></inertial>
  <collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision>
</link></robot>"""


# -- the joint operations in the raw protocol ------------------------------------------
def load(sim: Client, fmt: str, *, text: str | None = None, path: Path | None = None,
         prefix: str = "", fixed_base: bool = True, **extra: Any) -> list[str]:
    args: dict[str, Any] = {"format": fmt, "prefix": prefix, **extra}
    if text is not None:
        args["text"] = text
    if path is not None:
        args["path"] = str(path)
    if fmt == "urdf":
        args["fixed_base"] = fixed_base
    return list(sim.call("load_model", args)["names"])


def load_robot(sim: Client, robot: str, prefix: str = "") -> list[str]:
    """One of ROBOTS, sent as text with its folder as the search path (loading by path
    is tested on its own)."""
    path = ROBOTS[robot]
    return load(sim, "urdf", text=path.read_text(), prefix=prefix,
                search_path=str(path.parent))


def joints(sim: Client, **args: Any) -> list[JointInfo]:
    return [JointInfo.from_wire(j) for j in sim.call("joints", args)["joints"]]


@dataclass
class JointStates:
    names: list[str]
    positions: np.ndarray
    velocities: np.ndarray
    efforts: np.ndarray

    @classmethod
    def from_wire(cls, result: dict[str, Any]) -> JointStates:
        def column(key: str) -> np.ndarray:
            return unpack_f64(result[key], 1, key).reshape(-1)
        return cls(list(result["names"]), column("positions"), column("velocities"),
                   column("efforts"))


def values(data: float | Sequence[float] | np.ndarray) -> float | bytes:
    """A wire value: one number for every joint, or packed float64, one per joint."""
    if isinstance(data, int | float):
        return float(data)
    return pack_f64(np.asarray(data, dtype=float).reshape(-1))


def get_joint_states(sim: Client, names: Sequence[str] | None = None) -> JointStates:
    args = {} if names is None else {"names": list(names)}
    return JointStates.from_wire(sim.call("get_joint_states", args))


def set_joint_states(sim: Client, names: Sequence[str], positions: Any,
                     velocities: Any = None) -> None:
    args: dict[str, Any] = {"names": list(names), "positions": values(positions)}
    if velocities is not None:
        args["velocities"] = values(velocities)
    sim.call("set_joint_states", args)


def set_targets(sim: Client, names: Sequence[str], mode: str, targets: Any = None,
                **gains: Any) -> None:
    """set_joint_targets; ``gains`` are kp, kd, max_effort (numbers or arrays)."""
    args: dict[str, Any] = {"names": list(names), "mode": mode}
    if targets is not None:
        args["targets"] = values(targets)
    args.update({key: values(value) for key, value in gains.items()})
    sim.call("set_joint_targets", args)


def step_joints(sim: Client, count: int, names: Sequence[str]) -> JointStates:
    """step with read_joints: the joints' states after the last step, one round trip."""
    result = sim.call("step", {"count": count, "read_joints": list(names)})
    return JointStates.from_wire(result["joints"])


def apply_wrench(sim: Client, names: Sequence[str], wrenches: Any, *,
                 points: Any = None, duration: float | None = None) -> None:
    args: dict[str, Any] = {"names": list(names),
                            "wrenches": pack_f64(np.asarray(wrenches, float).reshape(-1, 6))}
    if points is not None:
        args["points"] = pack_f64(np.asarray(points, float).reshape(-1, 3))
    if duration is not None:
        args["duration"] = duration
    sim.call("apply_wrench", args)


# -- what a refused request must leave as it was ---------------------------------------
@dataclass
class ModelSnapshot:
    """The scene (support.Snapshot) with every joint's info and state."""

    scene: Snapshot
    joints: list[JointInfo]
    states: JointStates

    def assert_same(self, other: ModelSnapshot) -> None:
        self.scene.assert_same(other.scene)
        assert self.joints == other.joints
        assert self.states.names == other.states.names
        for key in ("positions", "velocities", "efforts"):
            assert np.array_equal(getattr(self.states, key), getattr(other.states, key)), key


def model_snapshot(sim: Client) -> ModelSnapshot:
    return ModelSnapshot(snapshot(sim), joints(sim), get_joint_states(sim))
