"""A loaded model's joints in PyBullet: what ``joints`` lists, and the actuator law the
engine applies to them every step.

PyBullet's own motors do not follow the protocol's law: POSITION_CONTROL and
VELOCITY_CONTROL are velocity constraints solved with a force cap, and PD_CONTROL is a
plugin's. So every 1-DOF joint's default velocity motor is switched off at load (force 0:
a joint with no target is free, as in MuJoCo), and each step the engine computes, for all
the joints of a model at once, the affine law MuJoCo's general actuators use,

    tau = clip(gain * target + bias_q * q + bias_v * qdot, -max_effort, max_effort)

(position: gain kp, bias_q -kp, bias_v -kd; velocity: gain kd, bias_v -kd; effort: gain
1; none: all 0), and hands it to PyBullet as TORQUE_CONTROL, which lasts one step. One
getJointStates and one setJointMotorControlArray per model per step, no loop per joint.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet_frames import rotate
from galton.protocol import JointInfo

TYPES = {pybullet.JOINT_REVOLUTE: "revolute", pybullet.JOINT_PRISMATIC: "prismatic",
         pybullet.JOINT_SPHERICAL: "spherical", pybullet.JOINT_FIXED: "fixed"}
SCALAR = (pybullet.JOINT_REVOLUTE, pybullet.JOINT_PRISMATIC)


@dataclass(slots=True)
class Articulation:
    """One model's links and joints, by entity and joint name (never by PyBullet id, so
    that the books outlive a rebuild), with the targets its 1-DOF joints hold."""

    root: str
    links: list[str]  # entity names; position j is PyBullet link j
    infos: list[JointInfo]  # as ``joints`` lists them
    scalar: dict[str, int]  # 1-DOF joint name -> its place in the arrays below
    indices: list[int]  # PyBullet joint index of each 1-DOF joint
    loaded: tuple[np.ndarray, np.ndarray]  # positions and velocities as loaded
    gain: np.ndarray = field(init=False)
    bias_q: np.ndarray = field(init=False)
    bias_v: np.ndarray = field(init=False)
    target: np.ndarray = field(init=False)
    max_effort: np.ndarray = field(init=False)
    effort: np.ndarray = field(init=False)  # what the last step applied
    active: bool = False  # whether any joint holds a target

    def __post_init__(self) -> None:
        self.release()

    def release(self) -> None:
        """Every target back to none."""
        n = len(self.indices)
        self.gain, self.bias_q, self.bias_v = np.zeros(n), np.zeros(n), np.zeros(n)
        self.target, self.effort = np.zeros(n), np.zeros(n)
        self.max_effort = np.full(n, np.inf)
        self.active = False
        for info in self.infos:
            info.mode = "none"

    def hold(self, places: list[int], mode: str, targets: np.ndarray, kp: np.ndarray,
             kd: np.ndarray, max_effort: np.ndarray) -> None:
        """Set the law's coefficients of these joints for ``mode``."""
        zero = np.zeros(len(places))
        gain, bias_q, bias_v = {
            "position": (kp, -kp, -kd), "velocity": (kd, zero, -kd),
            "effort": (np.ones(len(places)), zero, zero), "none": (zero, zero, zero)}[mode]
        self.gain[places], self.bias_q[places], self.bias_v[places] = gain, bias_q, bias_v
        self.target[places] = targets if mode != "none" else 0.0
        self.max_effort[places] = max_effort if mode != "none" else np.inf
        self.effort[places] = 0.0
        scalar = [info for info in self.infos if info.scalar]
        for place in places:
            scalar[place].mode = mode
        self.active = bool(self.gain.any() or self.bias_q.any() or self.bias_v.any())

    def actuate(self, bc: BulletClient, uid: int) -> None:
        """Apply the law for one step (TORQUE_CONTROL lasts one stepSimulation)."""
        states = bc.getJointStates(uid, self.indices)
        q = np.fromiter((s[0] for s in states), float, len(states))
        qdot = np.fromiter((s[1] for s in states), float, len(states))
        tau = self.gain * self.target + self.bias_q * q + self.bias_v * qdot
        self.effort = np.clip(tau, -self.max_effort, self.max_effort)
        bc.setJointMotorControlArray(uid, self.indices, pybullet.TORQUE_CONTROL,
                                     forces=self.effort.tolist())


def free_motors(bc: BulletClient, uid: int) -> None:
    """Switch off PyBullet's default velocity motors: a joint with no target is free."""
    indices = [j for j in range(bc.getNumJoints(uid)) if bc.getJointInfo(uid, j)[2] in SCALAR]
    if indices:
        bc.setJointMotorControlArray(uid, indices, pybullet.VELOCITY_CONTROL,
                                     forces=[0.0] * len(indices))


def articulation(bc: BulletClient, uid: int, root: str, links: list[str],
                 prefix: str, floating: bool) -> Articulation:
    """Read a freshly loaded body's joints (a floating base first, as ``root:free``)."""
    infos = [JointInfo(f"{root}:free", root, "free", "", root)] if floating else []
    scalar: dict[str, int] = {}
    indices: list[int] = []
    for j in range(bc.getNumJoints(uid)):
        info = joint_info(bc, uid, j, root, links, prefix)
        infos.append(info)
        if info.scalar:
            scalar[info.name] = len(indices)
            indices.append(j)
    states = bc.getJointStates(uid, indices) if indices else ()
    loaded = (np.array([s[0] for s in states], float), np.array([s[1] for s in states], float))
    return Articulation(root, links, infos, scalar, indices, loaded)


def joint_info(bc: BulletClient, uid: int, j: int, root: str, links: list[str],
               prefix: str) -> JointInfo:
    """One PyBullet joint as the protocol lists it: its axis turned from the child's
    inertial frame (PyBullet's) into its link frame; a continuous joint (PyBullet gives it
    lower > upper) unlimited; an effort or velocity limit of 0 (none given) as None."""
    info = bc.getJointInfo(uid, j)
    kind = TYPES.get(info[2], "fixed")
    scalar = info[2] in SCALAR
    axis = (0.0, 0.0, 0.0)
    if scalar:
        turn = np.array([bc.getDynamicsInfo(uid, j)[4]], float)
        unit = rotate(turn, np.array([info[13]], float))[0]
        unit /= np.linalg.norm(unit)
        axis = (float(unit[0]), float(unit[1]), float(unit[2]))
    limited = scalar and info[8] <= info[9]
    return JointInfo(
        name=prefix + info[1].decode("utf-8", "replace"), model=root, type=kind,
        parent=root if info[16] < 0 else links[info[16]], child=links[j], axis=axis,
        lower=float(info[8]) if limited else None, upper=float(info[9]) if limited else None,
        damping=float(info[6]), effort_limit=float(info[10]) if info[10] > 0 else None,
        velocity_limit=float(info[11]) if info[11] > 0 else None)
