"""A loaded model's joints in PyBullet: what ``joints`` lists, and the actuator law the
engine applies to them every step.

PyBullet's own motors do not follow the protocol's law: POSITION_CONTROL and
VELOCITY_CONTROL are velocity constraints solved with a force cap, and PD_CONTROL is a
plugin's. So every 1-DOF joint's default velocity motor is switched off at load (force 0:
a joint with no target is free, as in MuJoCo), and each step the engine computes, for all
the joints of a model at once, the affine law MuJoCo's general actuators use,

    tau = clip(gain * target + bias_q * q, -max_effort, max_effort) + bias_v * qdot

(position: gain kp, bias_q -kp, bias_v -kd; velocity: gain kd, bias_v -kd; effort: gain
1; none: all 0): max_effort bounds the drive, not the damping, on both engines. It hands
the torque to PyBullet as TORQUE_CONTROL, which lasts one step. One getJointStates and one
setJointMotorControlArray per model per step, no loop per joint.

Explicit, damping is unstable once its c·dt exceeds about twice a joint's inertia: kd 40
N·m·s on a kuka_iiwa's last link (6e-4 kg·m²) at 1/240 s, and even the file's own joint
damping (0.5 there), which Bullet applies explicitly, shake the arm at its velocity limit.
So while a model holds targets its damping (the targets' kd and the joints' own c) is
taken at the step's end velocity, as MuJoCo's Euler integrator takes joint damping
("stable PD"): with M the joint-space mass matrix and G the gravity and Coriolis torques
(PyBullet's own calculateMassMatrix and calculateInverseDynamics), D = dt (Kd + C), the
step's acceleration is a = (M + D)^-1 (tau - C qdot - G); the target applies tau - dt Kd a
(its effort) and the joints' own damping -C (qdot + dt a), of which Bullet applies -C qdot
itself. At rest this is the law itself, so a held pose and its effort are the law's. It
needs a fixed base whose movable joints are all 1-DOF (an arm on a table); any other model
keeps the explicit law.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import pybullet
from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.files import Axis, FileFacts
from galton.daemon.engines.pybullet.frames import rotate
from galton.protocol import JointInfo, NotFoundError

TYPES = {pybullet.JOINT_REVOLUTE: "revolute", pybullet.JOINT_PRISMATIC: "prismatic",
         pybullet.JOINT_SPHERICAL: "spherical", pybullet.JOINT_FIXED: "fixed"}
SCALAR = (pybullet.JOINT_REVOLUTE, pybullet.JOINT_PRISMATIC)


@dataclass(slots=True)
class Articulation:
    """One model's links and joints, by entity and joint name (never by PyBullet id, so
    that the records outlive a rebuild), with the targets its 1-DOF joints hold."""

    root: str
    links: list[str | None]  # entity names (None: hidden); position j is PyBullet link j
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
    fit: tuple[int, bool] = (-1, False)  # a PyBullet body, and whether it fits "stable PD"
    own_damping: np.ndarray = field(init=False)  # each 1-DOF joint's, as the file says

    def __post_init__(self) -> None:
        self.own_damping = np.array([i.damping for i in self.infos if i.scalar], float)
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

    def actuate(self, bc: BulletClient, uid: int, dt: float) -> None:
        """Apply the law for one step (TORQUE_CONTROL lasts one stepSimulation)."""
        states = bc.getJointStates(uid, self.indices)
        q = np.fromiter((s[0] for s in states), float, len(states))
        qdot = np.fromiter((s[1] for s in states), float, len(states))
        drive = np.clip(self.gain * self.target + self.bias_q * q, -self.max_effort,
                        self.max_effort)
        tau, own = drive + self.bias_v * qdot, np.zeros(len(drive))
        if (self.bias_v.any() or self.own_damping.any()) and self.fits(bc, uid):
            tau, own = self.damped_implicitly(bc, uid, q, qdot, tau, dt)
        self.effort = tau
        bc.setJointMotorControlArray(uid, self.indices, pybullet.TORQUE_CONTROL,
                                     forces=(self.effort + own).tolist())


    def damped_implicitly(self, bc: BulletClient, uid: int, q: np.ndarray, qdot: np.ndarray,
                          tau: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """The target's torque with its damping at the step's end velocity, and what to add
        for the joints' own damping to be so too (module docstring)."""
        mass = np.asarray(bc.calculateMassMatrix(uid, q.tolist()), float)
        bias = np.asarray(bc.calculateInverseDynamics(
            uid, q.tolist(), qdot.tolist(), [0.0] * len(q)), float)
        kd, own = -self.bias_v * dt, self.own_damping * dt
        accel = np.linalg.solve(mass + np.diag(kd + own),
                                tau - self.own_damping * qdot - bias)
        return tau - kd * accel, -own * accel


    def set_damping(self, bc: BulletClient, uid: int, places: list[int],
                    damping: np.ndarray) -> None:
        """These 1-DOF joints' own damping: Bullet's ``jointDamping`` of each joint's child
        link (stepSimulation applies -c qdot itself) and the books (its implicit part while
        targets are held, what ``joints`` lists and snapshots carry)."""
        scalar = [info for info in self.infos if info.scalar]
        for place, value in zip(places, damping.tolist(), strict=True):
            bc.changeDynamics(uid, self.indices[place], jointDamping=value)
            scalar[place].damping = value
        self.own_damping[places] = damping

    def apply_damping(self, bc: BulletClient, uid: int) -> None:
        """After the model is loaded again (a rebuild, a restore, a clone: its text gives
        the file's damping), each 1-DOF joint's as the books hold it."""
        for j, value in zip(self.indices, self.own_damping.tolist(), strict=True):
            if bc.getJointInfo(uid, j)[6] != value:
                bc.changeDynamics(uid, j, jointDamping=value)

    def fits(self, bc: BulletClient, uid: int) -> bool:
        """Whether the body's joint space is its 1-DOF joints' alone (a fixed base, no joint
        of several DOF), looked up once per PyBullet body (a rebuild makes a new one)."""
        if self.fit[0] != uid:
            movable = [j for j in range(bc.getNumJoints(uid))
                       if bc.getJointInfo(uid, j)[2] != pybullet.JOINT_FIXED]
            floating = any(info.type == "free" for info in self.infos)
            self.fit = (uid, not floating and movable == self.indices)
        return self.fit[1]


def set_damping(bc: BulletClient, models: dict[str, Articulation], uid_of: Callable[[str], int],
                names: Sequence[str], damping: np.ndarray) -> None:
    """Set these 1-DOF joints' own damping (>= 0, checked by the World)."""
    known = {name for model in models.values() for name in model.scalar}
    unknown = [name for name in names if name not in known]
    if unknown:
        raise NotFoundError(f"no joint with one degree of freedom named {unknown[0]!r} in "
                            "the PyBullet world")
    for root, model in models.items():
        rows = [row for row, name in enumerate(names) if name in model.scalar]
        if rows:
            model.set_damping(bc, uid_of(root), [model.scalar[names[r]] for r in rows],
                              np.asarray(damping, float)[rows])


def free_motors(bc: BulletClient, uid: int) -> None:
    """Switch off PyBullet's default velocity motors: a joint with no target is free."""
    indices = [j for j in range(bc.getNumJoints(uid)) if bc.getJointInfo(uid, j)[2] in SCALAR]
    if indices:
        bc.setJointMotorControlArray(uid, indices, pybullet.VELOCITY_CONTROL,
                                     forces=[0.0] * len(indices))


def articulation(bc: BulletClient, uid: int, root: str, links: list[str | None],
                 prefix: str, floating: bool, file: FileFacts) -> Articulation:
    """Read a freshly loaded body's joints (a floating base first: its MJCF free joint's
    name, else ``root:free``), those the file declares (not the welds PyBullet's MJCF
    importer adds)."""
    base = bc.getBodyInfo(uid)[0].decode("utf-8", "replace")
    free = prefix + file.free[base] if base in file.free else f"{root}:free"
    infos = [JointInfo(free, root, "free", "", root)] if floating else []
    scalar: dict[str, int] = {}
    indices: list[int] = []
    tree = Tree(bc, uid, root, links)
    for j in range(bc.getNumJoints(uid)):
        own = bc.getJointInfo(uid, j)[1].decode("utf-8", "replace")
        if file.hides_joint(own):
            continue
        info = joint_info(bc, uid, j, tree, prefix, file)
        infos.append(info)
        if info.scalar:
            scalar[info.name] = len(indices)
            indices.append(j)
    states = bc.getJointStates(uid, indices) if indices else ()
    loaded = (np.array([s[0] for s in states], float), np.array([s[1] for s in states], float))
    return Articulation(root, links, infos, scalar, indices, loaded)


class Tree:
    """A body's links as entities: a hidden link (an MJCF importer's joint link) stands
    for its nearest shown ancestor as a parent and its shown descendant as a child."""

    def __init__(self, bc: BulletClient, uid: int, root: str, links: list[str | None]) -> None:
        self.root, self.links = root, links
        self.parents = [bc.getJointInfo(uid, j)[16] for j in range(len(links))]
        self.children: dict[int, list[int]] = {}
        for j, parent in enumerate(self.parents):
            self.children.setdefault(parent, []).append(j)

    def parent(self, index: int) -> str:
        while index >= 0 and self.links[index] is None:
            index = self.parents[index]
        return self.root if index < 0 else self.links[index] or self.root

    def child(self, index: int) -> str:
        while self.links[index] is None and self.children.get(index):
            index = self.children[index][0]
        return self.links[index] or ""


def joint_info(bc: BulletClient, uid: int, j: int, tree: Tree, prefix: str,
               file: FileFacts) -> JointInfo:
    """One PyBullet joint as the protocol lists it: a URDF's axis and continuous joints as
    the file has them (files.py); an MJCF joint's axis turned from the child's
    inertial frame (PyBullet's) into its link frame; an effort or velocity limit of 0
    (none given) as None."""
    info = bc.getJointInfo(uid, j)
    own = info[1].decode("utf-8", "replace")
    kind, file_axis = file.joints.get(own, ("", None))
    scalar = info[2] in SCALAR
    axis = (0.0, 0.0, 0.0)
    if scalar:
        axis = file_axis or turned_axis(bc, uid, j, info[13])
    limited = scalar and info[8] <= info[9] and kind != "continuous"
    return JointInfo(
        name=prefix + own, model=tree.root, type=TYPES.get(info[2], "fixed"),
        parent=tree.parent(info[16]), child=tree.child(j), axis=axis,
        lower=float(info[8]) if limited else None, upper=float(info[9]) if limited else None,
        damping=file.damping.get(own, float(info[6])),
        effort_limit=float(info[10]) if info[10] > 0 else None,
        velocity_limit=float(info[11]) if info[11] > 0 else None)


def turned_axis(bc: BulletClient, uid: int, j: int, axis: Sequence[float]) -> Axis:
    """PyBullet's axis (in the child's inertial frame) in the child's link frame."""
    turn = np.array([bc.getDynamicsInfo(uid, j)[4]], float)
    unit = rotate(turn, np.array([axis], float))[0]
    unit /= np.linalg.norm(unit)
    return (float(unit[0]), float(unit[1]), float(unit[2]))
