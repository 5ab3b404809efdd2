"""Models' joints, the targets held on them and the wrenches held on bodies.

DART clears every joint force and external force after each step, so a held target or
wrench is applied again before every step: the target's drive (kp (target - q), kd target
or the effort, clipped to max_effort) on the joint's generalized force, a wrench as an
external force at the node's centre of mass plus an external torque, both in the world
frame. The target's damping kd goes into the joint's damping coefficient, which DART
integrates implicitly (at the step's end velocity), as the interface's law asks: an
explicit kd shakes a light link (docs/protocol.md, set_joint_targets).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from galton.daemon.engines.base import Target
from galton.protocol import InvalidArgumentError, JointInfo, NotFoundError

URDF_ROOT_JOINT = "rootJoint"  # DartLoader's joint of a URDF's root to the world
JOINT_TYPES = {"RevoluteJoint": "revolute", "PrismaticJoint": "prismatic",
               "BallJoint": "spherical", "FreeJoint": "free", "WeldJoint": "fixed"}


@dataclass
class Joint:
    """One joint of a loaded model, as joints() lists it, and its DART joint."""

    info: JointInfo
    joint: Any
    loaded: list[float]  # its positions as loaded


@dataclass
class Robots:
    """Every joint by name, targets and their last efforts, and held wrenches."""

    joints: dict[str, Joint] = field(default_factory=dict)
    targets: dict[str, Target] = field(default_factory=dict)
    efforts: dict[str, float] = field(default_factory=dict)
    wrenches: dict[str, tuple[Any, np.ndarray, np.ndarray]] = field(default_factory=dict)

    def busy(self) -> bool:
        return bool(self.targets or self.wrenches)

    def sync_damping(self) -> None:
        """Each 1-DOF joint's damping: its own, plus a held position or velocity target's kd."""
        for name, joint in self.joints.items():
            if not joint.info.scalar:
                continue
            target = self.targets.get(name)
            damped = target is not None and target.mode in ("position", "velocity")
            wanted = joint.info.damping + (target.kd if damped and target else 0.0)
            if joint.joint.getDampingCoefficient(0) != wanted:
                joint.joint.setDampingCoefficient(0, wanted)

    def set_damping(self, names: Sequence[str], damping: np.ndarray) -> None:
        """These 1-DOF joints' own damping (the joint's damping coefficient, beside a held
        target's kd: sync_damping before each step), which DART integrates implicitly."""
        for joint, value in zip(self.scalar(names), np.asarray(damping, float).tolist(),
                                strict=True):
            joint.info.damping = value
        self.sync_damping()

    def own_damping(self) -> dict[str, float]:
        """Each 1-DOF joint's own damping, for a snapshot (a restore loads the file's)."""
        return {name: joint.info.damping for name, joint in self.joints.items()
                if joint.info.scalar}

    def put_back_damping(self, damping: dict[str, Any]) -> None:
        """A snapshot's damping (``own_damping``) on the joints a restore loaded again."""
        self.set_damping(list(damping), np.array([float(v) for v in damping.values()]))

    def effort(self, name: str) -> float:
        """What the joint's target applied in the last step: its drive and its damping at
        the velocity the step ended with."""
        target = self.targets.get(name)
        if target is None:
            return 0.0
        drive = self.efforts.get(name, 0.0)
        if target.mode in ("position", "velocity"):
            return drive - target.kd * float(self.joints[name].joint.getVelocity(0))
        return drive

    def actuate(self) -> None:
        """Apply every held target's drive and every wrench for the coming step."""
        for name, target in self.targets.items():
            joint = self.joints[name].joint
            tau = target_drive(target, joint.getPosition(0))
            joint.setForce(0, tau)
            self.efforts[name] = tau
        for node, force, torque in self.wrenches.values():
            node.addExtForce(force, node.getLocalCOM(), False, True)
            node.addExtTorque(torque, False)

    def forget_model(self, model: str) -> None:
        """Drop a deleted model's joints, targets and wrenches."""
        for name in [n for n, j in self.joints.items() if j.info.model == model]:
            del self.joints[name]
            self.targets.pop(name, None)
            self.efforts.pop(name, None)

    def scalar(self, names: Sequence[str]) -> list[Joint]:
        """These 1-DOF joints (NotFoundError, InvalidArgumentError otherwise)."""
        found = []
        for name in names:
            joint = self.joints.get(name)
            if joint is None:
                raise NotFoundError(f"no joint named {name!r} in the DART world")
            if not joint.info.scalar:
                raise InvalidArgumentError(
                    f"joint {name!r} is {joint.info.type}: only revolute and prismatic "
                    "joints have joint states (a free joint's body: use get_states)")
            found.append(joint)
        return found


def target_drive(target: Target, q: float) -> float:
    """The law's drive (its damping is the joint's: Robots.sync_damping), clipped."""
    if target.mode == "position":
        tau = target.kp * (target.target - q)
    elif target.mode == "velocity":
        tau = target.kd * target.target
    elif target.mode == "effort":
        tau = target.target
    else:
        tau = 0.0
    return float(np.clip(tau, -target.max_effort, target.max_effort))


def describe(skeleton: Any, prefix: str, model: str, links: dict[int, str]) -> list[Joint]:
    """The skeleton's joints: a welded root left out, a URDF's free root named
    ``root:free`` as on the other engines."""
    found = []
    for joint in skeleton.getJoints():
        kind = JOINT_TYPES.get(joint.getType())
        parent = joint.getParentBodyNode()
        if kind is None or (parent is None and kind == "fixed"):
            continue
        child = links[id_of(joint.getChildBodyNode())]
        name = f"{model}:free" if joint.getName() == URDF_ROOT_JOINT else (
            prefix + joint.getName())
        info = JointInfo(name=name, model=model, type=kind,
                         parent="" if parent is None else links[id_of(parent)], child=child,
                         **_axis_and_limits(joint, kind))
        found.append(Joint(info, joint, [float(v) for v in joint.getPositions()]))
    return found


def id_of(node: Any) -> int:
    return int(node.getIndexInSkeleton())


def _axis_and_limits(joint: Any, kind: str) -> dict[str, Any]:
    if kind not in ("revolute", "prismatic"):
        return {}
    turn = np.asarray(joint.getTransformFromChildBodyNode().rotation(), dtype=float)
    axis = turn @ np.asarray(joint.getAxis(), dtype=float)  # in the child link's frame
    lower, upper = joint.getPositionLowerLimit(0), joint.getPositionUpperLimit(0)
    if not lower < upper:  # unlimited (dartpy reads MJCF's as 0..0)
        lower, upper = -np.inf, np.inf
    effort, speed = joint.getForceUpperLimit(0), joint.getVelocityUpperLimit(0)
    return {"axis": (float(axis[0]), float(axis[1]), float(axis[2])),
            "lower": float(lower) if np.isfinite(lower) else None,
            "upper": float(upper) if np.isfinite(upper) else None,
            "damping": float(joint.getDampingCoefficient(0)),
            "effort_limit": float(effort) if np.isfinite(effort) else None,
            "velocity_limit": float(speed) if np.isfinite(speed) else None}
