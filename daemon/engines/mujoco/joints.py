"""Loaded models' joints in the MuJoCo world: their descriptions, states and held targets.

Every 1-DOF joint has one general actuator of its own name (``model_setup``); a target is
written into that actuator's gain, bias, control and force range, and its damping into the
joint's own damping, so MuJoCo applies the PD law itself in every step:

    position: gain kp, bias (0, -kp, 0), ctrl = target, damping + kd -> kp (target - q) - kd qdot
    velocity: gain kd, bias 0,           ctrl = target, damping + kd -> kd (target - qdot)
    effort:   gain 1,  bias 0,           ctrl = target               -> target
    none:     everything 0                                           -> 0

The actuator's part is clipped by MuJoCo to the force range +-max_effort when finite. The
damping part goes into ``dof_damping`` because MuJoCo's Euler integrator applies joint
damping implicitly (at the step's end velocity): as an actuator bias it is explicit, and a
kd that robot users type (40 N·m·s on a kuka_iiwa's light last link, whose inertia is
~1e-3 kg·m²) makes kd·dt/I far above 2, so the arm shakes and diverges. Implicit, any kd is
stable; it is not clipped by max_effort. The efforts read are the law's whole value.

The compiled values are lost to a recompile, so the held targets are kept here by joint
name and written again after each one (``apply``); states and targets are read and written
through index arrays, one numpy operation per call.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import mujoco
import numpy as np

from galton.daemon.engines.base import Target
from galton.daemon.engines.mujoco.model_setup import Facts, entity_name, fixed_joint_name
from galton.protocol import InvalidArgumentError, JointInfo, NotFoundError

JOINT_TYPES = {mujoco.mjtJoint.mjJNT_FREE: "free", mujoco.mjtJoint.mjJNT_BALL: "spherical",
               mujoco.mjtJoint.mjJNT_SLIDE: "prismatic", mujoco.mjtJoint.mjJNT_HINGE: "revolute"}
_WIDTHS = {mujoco.mjtJoint.mjJNT_BALL: (4, 3)}  # qpos, qvel rows; 1-DOF joints: (1, 1)
_FREE = mujoco.mjtJoint.mjJNT_FREE


class Joints:
    """The engine's records of joints: descriptions by model, targets by joint, and where each
    1-DOF joint's state and actuator live in the compiled model."""

    def __init__(self) -> None:
        self.infos: dict[str, list[JointInfo]] = {}  # by model root entity, load order
        self.targets: dict[str, Target] = {}
        self.slot: dict[str, int] = {}  # 1-DOF joint -> its actuator's id
        self.qadr = np.zeros(0, dtype=np.int64)  # by actuator id
        self.vadr = np.zeros(0, dtype=np.int64)
        self.own: dict[str, float] = {}  # 1-DOF joint -> its damping as loaded
        self.own_damping = np.zeros(0)  # by actuator id: the same
        self.target_damping = np.zeros(0)  # by actuator id: what a held target adds

    def copy(self) -> Joints:
        """An independent copy of the records (a fork's, a kept state's)."""
        joints = Joints()
        joints.infos = {root: list(infos) for root, infos in self.infos.items()}
        joints.targets = dict(self.targets)  # Target is frozen
        joints.slot = dict(self.slot)
        joints.qadr, joints.vadr = self.qadr.copy(), self.vadr.copy()
        joints.own, joints.own_damping = dict(self.own), self.own_damping.copy()
        joints.target_damping = self.target_damping.copy()
        return joints

    # -- records -----------------------------------------------------------------------------
    def reindex(self, m: mujoco.MjModel) -> None:
        """Where the joints live after a compile (actuators are ours alone, one per joint)."""
        self.slot = {mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_ACTUATOR, a): a
                     for a in range(m.nu)}
        joint = m.actuator_trnid[:, 0]
        self.qadr = m.jnt_qposadr[joint].astype(np.int64)
        self.vadr = m.jnt_dofadr[joint].astype(np.int64)
        for name, a in self.slot.items():  # a joint new to the records has its compiled value
            self.own.setdefault(name, float(m.dof_damping[self.vadr[a]]))
        self.own_damping = np.array([self.own[name] for name in self.slot], float)
        self.target_damping = np.zeros(m.nu)

    def add_model(self, root: str, infos: list[JointInfo]) -> None:
        self.infos[root] = infos

    def forget_model(self, root: str) -> None:
        for info in self.infos.pop(root, []):
            self.targets.pop(info.name, None)
            self.own.pop(info.name, None)

    def describe(self) -> list[JointInfo]:
        """Every joint, in load order, with the mode it holds now."""
        return [replace(info, mode=self.mode(info.name))
                for infos in self.infos.values() for info in infos]

    def mode(self, joint: str) -> str:
        held = self.targets.get(joint)
        return "none" if held is None else held.mode

    def actuators(self, names: Sequence[str]) -> np.ndarray:
        """The actuator ids of these 1-DOF joints; a typed error for any other name."""
        try:
            return np.fromiter((self.slot[n] for n in names), dtype=np.int64,
                               count=len(names))
        except KeyError as exc:
            name = exc.args[0]
            if any(i.name == name for infos in self.infos.values() for i in infos):
                raise InvalidArgumentError(f"joint {name!r} has not one degree of freedom: "
                                           "only revolute and prismatic joints have a "
                                           "state and a target") from exc
            raise NotFoundError(f"no joint named {name!r} in the MuJoCo world") from exc

    # -- states ----------------------------------------------------------------------------
    def read(self, d: mujoco.MjData, names: Sequence[str]
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions, velocities and the targets' efforts of the last step (the actuator's
        part and the implicit damping's, at the velocity the step ended with)."""
        aid = self.actuators(names)
        velocities = d.qvel[self.vadr[aid]]
        efforts = d.actuator_force[aid] - self.target_damping[aid] * velocities
        return d.qpos[self.qadr[aid]], velocities, efforts

    def write(self, d: mujoco.MjData, names: Sequence[str], positions: np.ndarray,
              velocities: np.ndarray | None) -> None:
        aid = self.actuators(names)
        d.qpos[self.qadr[aid]] = positions
        if velocities is not None:
            d.qvel[self.vadr[aid]] = velocities

    # -- damping ---------------------------------------------------------------------------
    def set_damping(self, m: mujoco.MjModel, names: Sequence[str], damping: np.ndarray) -> None:
        """These 1-DOF joints' own damping (``dof_damping``, beside a held target's kd): kept
        by name across recompiles (``own``) and in the descriptions, so snapshots carry it."""
        aid = self.actuators(names)
        wanted = {name: float(value) for name, value in zip(names, damping, strict=True)}
        self.own.update(wanted)
        self.own_damping[aid] = damping
        m.dof_damping[self.vadr[aid]] = self.own_damping[aid] + self.target_damping[aid]
        self.infos = {root: [replace(i, damping=wanted[i.name]) if i.name in wanted else i
                             for i in infos] for root, infos in self.infos.items()}

    # -- targets ---------------------------------------------------------------------------
    def hold(self, m: mujoco.MjModel, d: mujoco.MjData, names: Sequence[str], mode: str,
             targets: np.ndarray, kp: np.ndarray, kd: np.ndarray,
             max_effort: np.ndarray) -> None:
        aid = self.actuators(names)
        self.write_law(m, d, aid, mode, targets, kp, kd, max_effort)
        for row, name in enumerate(names):
            if mode == "none":
                self.targets.pop(name, None)
            else:
                self.targets[name] = Target(mode, float(targets[row]), float(kp[row]),
                                            float(kd[row]), float(max_effort[row]))

    def apply(self, m: mujoco.MjModel, d: mujoco.MjData) -> None:
        """Write every held target into the compiled model (after a compile), and none into
        the other actuators."""
        if m.nu:
            self.write_law(m, d, np.arange(m.nu), "none", *np.zeros((4, m.nu)))
        for mode in {t.mode for t in self.targets.values()}:
            names = [n for n, t in self.targets.items() if t.mode == mode]
            rows = np.array([[t.target, t.kp, t.kd, t.max_effort]
                             for t in self.targets.values() if t.mode == mode])
            self.write_law(m, d, self.actuators(names), mode, *rows.T)

    def write_law(self, m: mujoco.MjModel, d: mujoco.MjData, aid: np.ndarray, mode: str,
              targets: np.ndarray, kp: np.ndarray, kd: np.ndarray,
              max_effort: np.ndarray) -> None:
        """One mode's targets into these actuators and their joints' damping."""
        write_targets(m, d, aid, mode, targets, kp, kd, max_effort)
        damped = kd if mode in ("position", "velocity") else np.zeros(len(aid))
        self.target_damping[aid] = damped
        m.dof_damping[self.vadr[aid]] = self.own_damping[aid] + damped

    def restore(self, m: mujoco.MjModel, d: mujoco.MjData, roots: np.ndarray) -> None:
        """Every joint of these models but a root's free one back to its as-loaded value at
        rest, every target dropped, no actuator force left from the last step."""
        self.targets.clear()
        self.apply(m, d)
        d.actuator_force[:] = 0.0
        moving = np.isin(m.body_rootid[m.jnt_bodyid], roots) & (m.jnt_type != _FREE)
        for j in np.flatnonzero(moving).tolist():
            qwidth, vwidth = _WIDTHS.get(int(m.jnt_type[j]), (1, 1))
            qadr, vadr = m.jnt_qposadr[j], m.jnt_dofadr[j]
            d.qpos[qadr:qadr + qwidth] = m.qpos0[qadr:qadr + qwidth]
            d.qvel[vadr:vadr + vwidth] = 0.0


def write_targets(m: mujoco.MjModel, d: mujoco.MjData, aid: np.ndarray, mode: str,
                  targets: np.ndarray, kp: np.ndarray, kd: np.ndarray,
                  max_effort: np.ndarray) -> None:
    """One mode's targets into these actuators, but their damping (module docstring)."""
    zero = np.zeros(len(aid))
    gain = {"position": kp, "velocity": kd, "effort": np.ones(len(aid))}.get(mode, zero)
    m.actuator_gainprm[aid, 0] = gain
    m.actuator_biasprm[aid, 0] = 0.0
    m.actuator_biasprm[aid, 1] = -kp if mode == "position" else zero
    m.actuator_biasprm[aid, 2] = 0.0  # the damping is the joint's (Joints.write_law)
    d.ctrl[aid] = zero if mode == "none" else targets
    limited = np.isfinite(max_effort)
    m.actuator_forcelimited[aid] = limited
    bound = np.where(limited, max_effort, 0.0)
    m.actuator_forcerange[aid, 0] = -bound
    m.actuator_forcerange[aid, 1] = bound


# -- descriptions ----------------------------------------------------------------------------
def describe_model(m: mujoco.MjModel, root: int, model: str, prefix: str,
                   facts: Facts) -> list[JointInfo]:
    """The joints of the model rooted at body ``root``, body by body in MuJoCo's order: each
    body's joints, or a fixed joint for a jointless link."""
    infos: list[JointInfo] = []
    for body in np.flatnonzero(m.body_rootid == root).tolist():
        child = entity_name(m.body(body).name)
        parent = "" if body == root else entity_name(m.body(int(m.body_parentid[body])).name)
        first, count = int(m.body_jntadr[body]), int(m.body_jntnum[body])
        for j in range(first, first + count):
            infos.append(joint_info(m, j, model, parent, child, prefix, facts))
        if count == 0 and body != root:
            bare = child[len(prefix):]
            name = prefix + facts.fixed[bare] if bare in facts.fixed else \
                fixed_joint_name(child)
            infos.append(JointInfo(name=name, model=model, type="fixed", parent=parent,
                                   child=child))
    return infos


def joint_info(m: mujoco.MjModel, j: int, model: str, parent: str, child: str, prefix: str,
               facts: Facts) -> JointInfo:
    kind = JOINT_TYPES[mujoco.mjtJoint(int(m.jnt_type[j]))]
    name = m.joint(j).name
    bare = name[len(prefix):]
    scalar = kind in ("revolute", "prismatic")
    axis = m.jnt_axis[j] / np.linalg.norm(m.jnt_axis[j]) if scalar else np.zeros(3)
    limited = scalar and bool(m.jnt_limited[j])
    return JointInfo(
        name=name, model=model, type=kind, parent=parent, child=child,
        axis=(float(axis[0]), float(axis[1]), float(axis[2])),
        lower=float(m.jnt_range[j, 0]) if limited else None,
        upper=float(m.jnt_range[j, 1]) if limited else None,
        damping=float(m.dof_damping[m.jnt_dofadr[j]]),
        effort_limit=facts.effort.get(bare), velocity_limit=facts.velocity.get(bare))
