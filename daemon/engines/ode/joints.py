"""Loaded robots' joints: ODE hinges and sliders (URDF revolute, continuous, prismatic),
ODE fixed joints (URDF fixed, and a fixed base to the world), the targets held on them and
the rewind to the as-loaded state.

A target follows the interface's law, clipped to max_effort: position tau = kp (target - q)
- kd q̇, velocity tau = kd (target - q̇), effort tau = target. The spring and effort parts are
joint torques (forces) added before each step; the damping part is ODE's joint motor, a
velocity constraint whose CFM 1 / kd makes it exactly a damper solved implicitly with the
step, so the gains robot users type hold at the default step: for a position target the
spring is clipped to max_effort and the damper is not, for a velocity target the damper is
the drive, at most max_effort. The reported effort is the law with the velocity the step
ends with (``settle``). URDF damping adds -damping q̇ beside it (explicit, not counted in
the effort). Limits are ODE's stops.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from galton.daemon.engines.ode import frames
from galton.daemon.engines.ode import state as states
from galton.daemon.engines.ode.native import LIB
from galton.daemon.engines.ode.spawn import Body
from galton.protocol import InvalidArgumentError, JointInfo, NotFoundError
from galton.protocol.errors import did_you_mean
from galton.protocol.vocabulary import MAX_EFFORT

LO_STOP, HI_STOP, MOTOR_VELOCITY, MOTOR_MAX_FORCE, MOTOR_CFM = 0, 1, 2, 5, 8  # ODE's dParam*
HINGES = ("revolute", "continuous")


@dataclass
class Joint:
    """One URDF joint in ODE."""

    info: JointInfo
    handle: int  # the ODE joint (0 for none)
    origin: frames.Frame  # the joint's frame in its parent link's frame
    axis: np.ndarray  # unit, in the joint's (and child's) frame
    target: float = 0.0
    kp: float = 0.0
    kd: float = 0.0
    max_effort: float = np.inf
    effort: float = 0.0
    pushed: float = 0.0  # the explicit part applied for the current step

    @property
    def scalar(self) -> bool:
        return self.info.type in (*HINGES, "prismatic")

    def read(self) -> tuple[float, float]:
        if self.info.type in HINGES:
            return (float(LIB.dJointGetHingeAngle(self.handle)),
                    float(LIB.dJointGetHingeAngleRate(self.handle)))
        if self.info.type == "prismatic":
            return (float(LIB.dJointGetSliderPosition(self.handle)),
                    float(LIB.dJointGetSliderPositionRate(self.handle)))
        return 0.0, 0.0

    def motion(self, q: float) -> frames.Frame:
        """The child's frame in the joint's frame at position q."""
        if self.info.type in HINGES:
            return np.zeros(3), frames.axis_angle(self.axis, q)
        if self.info.type == "prismatic":
            return self.axis * q, frames.IDENTITY[1]
        return frames.IDENTITY

    def motor(self, velocity: float, damping: float, max_force: float) -> None:
        """ODE's motor as a damper: force damping (velocity - q̇), at most max_force; off
        for no damping."""
        set_param = LIB.dJointSetHingeParam if self.info.type in HINGES else \
            LIB.dJointSetSliderParam
        on = damping > 0 and max_force > 0
        set_param(self.handle, MOTOR_VELOCITY, velocity if on else 0.0)
        set_param(self.handle, MOTOR_CFM, 1.0 / damping if on else 1e-5)
        set_param(self.handle, MOTOR_MAX_FORCE, min(max_force, 1e30) if on else 0.0)

    def push(self, tau: float) -> None:
        if self.info.type in HINGES:
            LIB.dJointAddHingeTorque(self.handle, tau)
        else:
            LIB.dJointAddSliderForce(self.handle, tau)


@dataclass
class Model:
    root: str
    links: list[str]  # root first, then in load order
    joints: list[Joint]  # parents before children
    free: JointInfo | None = None  # a floating base's free joint (its root's pose)
    source: dict[str, Any] = field(default_factory=dict)  # how it was loaded (snapshots)


@dataclass
class Robots:
    """Every loaded model's links and joints."""

    models: dict[str, Model] = field(default_factory=dict)
    by_name: dict[str, Joint] = field(default_factory=dict)
    links: set[str] = field(default_factory=set)

    def add(self, model: Model) -> None:
        self.models[model.root] = model
        self.links.update(model.links)
        self.by_name.update((j.info.name, j) for j in model.joints)

    def busy(self) -> bool:
        return any(j.info.mode != "none" or j.info.damping > 0 for j in self.by_name.values())

    def actuate(self) -> None:
        """Apply every held target (and URDF damping) for the coming step."""
        for joint in self.by_name.values():
            if not joint.scalar:
                continue
            mode, damping = joint.info.mode, joint.info.damping
            if mode == "none" and damping <= 0:
                continue
            q, rate = joint.read()
            limit = min(joint.max_effort, MAX_EFFORT)  # no law pushes past the protocol's bound
            explicit = 0.0  # what is pushed now; the motor adds the damping with the step
            if mode == "position":
                explicit = float(np.clip(joint.kp * (joint.target - q), -limit, limit))
                tau = joint.kp * (joint.target - q) - joint.kd * rate
            elif mode == "velocity":
                tau = joint.kd * (joint.target - rate)
            elif mode == "effort":
                tau = explicit = float(np.clip(joint.target, -limit, limit))
            else:
                tau = 0.0
            joint.effort = float(np.clip(tau, -limit, limit))
            joint.pushed = explicit
            joint.push(explicit - damping * rate)

    def settle(self) -> None:
        """The efforts of the step just taken: the damper's part at the velocity it ended
        with (ODE solved it with the step)."""
        for joint in self.by_name.values():
            mode = joint.info.mode
            if mode == "position":
                joint.effort = joint.pushed - joint.kd * joint.read()[1]
            elif mode == "velocity":
                joint.effort = float(np.clip(joint.kd * (joint.target - joint.read()[1]),
                                             -joint.max_effort, joint.max_effort))

    def infos(self) -> list[JointInfo]:
        return [info for m in self.models.values()
                for info in ([m.free] if m.free else []) + [j.info for j in m.joints]]

    def links_of(self, root: str, bodies: dict[str, Body]) -> list[Body]:
        model = self.models.get(root)
        return [] if model is None else [bodies[n] for n in model.links if n in bodies]

    def model_mass(self, root: str, bodies: dict[str, Body]) -> float:
        return float(sum(b.mass for b in self.links_of(root, bodies)))

    def forget(self, root: str) -> None:
        model = self.models.pop(root, None)
        if model is None:
            return
        for name in model.links:
            self.links.discard(name)
        for joint in model.joints:
            self.by_name.pop(joint.info.name, None)
            if joint.handle:
                LIB.dJointDestroy(joint.handle)

    def destroy(self) -> None:
        for root in list(self.models):
            self.forget(root)

    def _scalar(self, names: Sequence[str]) -> list[Joint]:
        found = []
        for name in names:
            joint = self.by_name.get(name)
            if joint is None:
                raise NotFoundError(f"no joint named {name!r}{did_you_mean(name, self.by_name)}")
            if not joint.scalar:
                raise InvalidArgumentError(f"joint {name!r} is {joint.info.type}: it has no "
                                           "position to read or drive")
            found.append(joint)
        return found

    def set_damping(self, names: Sequence[str], damping: np.ndarray,
                    bodies: dict[str, Body]) -> None:
        """These 1-DOF joints' own damping. ODE has no joint damping of its own: as Webots
        does for a joint's ``dampingConstant``, ``actuate`` pushes -damping q̇ on the joint
        before each step (explicit, beside a target's law), as it does for URDF damping."""
        for joint, value in zip(self._scalar(names), np.asarray(damping, float).tolist(),
                                strict=True):
            joint.info.damping = value
            for link in (joint.info.parent, joint.info.child):
                if link in bodies and not bodies[link].static:
                    states.wake(bodies[link])

    def put_back_damping(self, name: str, value: Any) -> None:
        """A snapshot's damping of one joint (a restore loads the file's first)."""
        if not isinstance(value, (int, float)) or not 0.0 <= float(value) < np.inf:
            raise InvalidArgumentError(f"not an ode snapshot: joint {name!r}'s damping "
                                       f"{value!r} is not a finite number >= 0")
        self._scalar([name])[0].info.damping = float(value)

    def states(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        joints = self._scalar(names)
        read = [j.read() for j in joints]
        return (np.array([r[0] for r in read], dtype=float),
                np.array([r[1] for r in read], dtype=float),
                np.array([j.effort for j in joints], dtype=float))

    def teleport(self, names: Sequence[str], positions: np.ndarray,
                 velocities: np.ndarray | None, bodies: dict[str, Body]) -> None:
        joints = self._scalar(names)
        wanted = {j.info.name: (float(positions[k]), None if velocities is None
                                else float(velocities[k])) for k, j in enumerate(joints)}
        for model in {id(m): m for m in self.models.values()
                      if any(j.info.name in wanted for j in m.joints)}.values():
            place(model, bodies, wanted)

    def hold(self, names: Sequence[str], mode: str, targets: np.ndarray, kp: np.ndarray,
             kd: np.ndarray, max_effort: np.ndarray, bodies: dict[str, Body]) -> None:
        joints = self._scalar(names)
        for k, joint in enumerate(joints):
            joint.info.mode = mode
            joint.target, joint.kp, joint.kd = float(targets[k]), float(kp[k]), float(kd[k])
            joint.max_effort = float(max_effort[k])
            if mode == "position":
                joint.motor(0.0, joint.kd, np.inf)
            elif mode == "velocity":
                joint.motor(joint.target, joint.kd, joint.max_effort)
            else:
                joint.motor(0.0, 0.0, 0.0)
            if mode == "none":
                joint.effort = 0.0
            for link in (joint.info.parent, joint.info.child):
                if link in bodies and not bodies[link].static:
                    states.wake(bodies[link])

    def rewind(self, bodies: dict[str, Body]) -> None:
        """Every joint at 0 (as loaded) and at rest, no target."""
        for model in self.models.values():
            for joint in model.joints:
                joint.info.mode, joint.effort = "none", 0.0
                if joint.scalar:
                    joint.motor(0.0, 0.0, 0.0)
            place(model, bodies, {j.info.name: (0.0, 0.0) for j in model.joints if j.scalar})


def place(model: Model, bodies: dict[str, Body],
          wanted: dict[str, tuple[float, float | None]]) -> None:
    """Put every link where its joints' positions (``wanted``, else as they are) put it
    from the root, moving as their velocities make it move (else as they are)."""
    root = bodies[model.root]
    poses, twists = states.read([root])
    frame = {model.root: (poses[0][:3], poses[0][3:])}
    twist = {model.root: twists[0]}
    for joint in model.joints:
        q, rate = joint.read()
        q, new_rate = wanted.get(joint.info.name, (q, rate))
        rate = rate if new_rate is None else new_rate
        parent = frame[joint.info.parent]
        at_joint = frames.compose(parent, joint.origin)
        child = frames.compose(at_joint, joint.motion(q))
        axis = frames.rotate(at_joint[1], joint.axis)
        v, w = twist[joint.info.parent][:3], twist[joint.info.parent][3:]
        linear = v + np.cross(w, child[0] - parent[0])
        if joint.info.type in HINGES:
            w = w + axis * rate
        elif joint.info.type == "prismatic":
            linear = linear + axis * rate
        frame[joint.info.child], twist[joint.info.child] = child, np.concatenate([linear, w])
    for name in model.links[1:]:
        body = bodies[name]
        pose = np.concatenate(frame[name])
        states.write([body], pose[None], None)
        states.write([body], None, twist[name][None])
