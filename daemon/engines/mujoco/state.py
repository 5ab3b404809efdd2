"""Where a compiled MuJoCo world keeps each body's state, and reading and writing it in batches.

Poses on the wire are [x y z qx qy qz qw] and twists [vx vy vz wx wy wz], both in the world
frame; MuJoCo keeps quaternions w x y z and a free joint's angular velocity in the body frame.
Everything here works on index arrays, one numpy operation per kind of body, never per body
per step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from galton.protocol import FeatureUnsupportedError

FREE, MOCAP, JOINTED, STATIC = 1, 2, 3, 4
# How far a jointed body's requested pose may be from its initial one (m, quaternion units).
_SAME_POSE = 1e-6
POSE = np.arange(7)
TWIST = np.arange(6)


# -- quaternions: MuJoCo is w x y z, the wire x y z w -----------------------------------
def to_wxyz(xyzw: np.ndarray) -> np.ndarray:
    return xyzw[..., [3, 0, 1, 2]]


def to_xyzw(wxyz: np.ndarray) -> np.ndarray:
    return wxyz[..., [1, 2, 3, 0]]


def rotate(wxyz: np.ndarray, vec: np.ndarray, *, inverse: bool = False) -> np.ndarray:
    """Rotate rows of vectors by rows of unit quaternions (or by their inverses).

    A non-finite vector comes out non-finite (0 x inf is NaN) without a RuntimeWarning:
    state_within is what reports a diverged state, not a warning on the way to it."""
    w = wxyz[:, :1]
    u = -wxyz[:, 1:] if inverse else wxyz[:, 1:]
    with np.errstate(invalid="ignore", over="ignore"):
        t = 2.0 * np.cross(u, vec)
        return vec + w * t + np.cross(u, t)


# -- compiled model: where states live ---------------------------------------------------
@dataclass(frozen=True)
class StateIndex:
    """Per body id: how it moves (FREE, MOCAP, JOINTED, STATIC) and where its state lives.

    STATIC: a jointless, non-mocap child of the world, posed by the model's body_pos/quat.
    Also, for the divergence check: the qvel rows of free joints' angular velocities (in the
    body frame) with the qpos rows of their quaternions, every other qvel row, and the bodies
    moved by joints other than a free one.
    """

    kind: np.ndarray
    qadr: np.ndarray
    vadr: np.ndarray
    mocap: np.ndarray
    spin_dofs: np.ndarray  # (n, 3)
    spin_quats: np.ndarray  # (n, 4)
    other_dofs: np.ndarray
    jointed: np.ndarray

    @classmethod
    def of(cls, m: mujoco.MjModel) -> StateIndex:
        jnt = np.maximum(m.body_jntadr, 0)
        free = np.zeros(m.nbody, dtype=bool)
        qadr = vadr = np.full(m.nbody, -1)
        if m.njnt:
            free = (m.body_jntnum == 1) & (m.jnt_type[jnt] == mujoco.mjtJoint.mjJNT_FREE)
            qadr = np.where(free, m.jnt_qposadr[jnt], -1)
            vadr = np.where(free, m.jnt_dofadr[jnt], -1)
        static = (m.body_parentid == 0) & (m.body_jntnum == 0) & (m.body_mocapid < 0)
        static[0] = False
        kind = np.where(free, FREE, np.where(m.body_mocapid >= 0, MOCAP,
                                             np.where(static, STATIC, JOINTED)))
        spin = vadr[free][:, None] + TWIST[3:]
        other = np.ones(m.nv, dtype=bool)
        other[spin.ravel()] = False
        jointed = np.flatnonzero(kind == JOINTED)
        return cls(kind=kind, qadr=qadr, vadr=vadr, mocap=m.body_mocapid.copy(),
                   spin_dofs=spin, spin_quats=qadr[free][:, None] + POSE[3:],
                   other_dofs=np.flatnonzero(other), jointed=jointed[jointed > 0])


def jointed_states(m: mujoco.MjModel, d: mujoco.MjData,
                   ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pose and world twist of the frames of bodies held by joints other than a free one
    (a link's frame: its origin, not its centre of mass).

    MuJoCo's cvel is a body's (angular, linear) velocity at its tree's centre of mass; the
    frame origin's linear velocity is v + w x (origin - that centre), as mj_objectVelocity
    computes it for one body."""
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    mujoco.mj_comVel(m, d)
    spin, linear = d.cvel[ids, :3], d.cvel[ids, 3:]
    offset = d.xpos[ids] - d.subtree_com[m.body_rootid[ids]]
    twists = np.hstack([linear + np.cross(spin, offset), spin])
    return np.hstack([d.xpos[ids], to_xyzw(d.xquat[ids])]), twists


def check_jointed(name: str, initial: np.ndarray | None, pose: np.ndarray | None,
                  twist: np.ndarray | None) -> None:
    """A body held by joints can only be put back, at rest, where it was loaded."""
    moved = pose is not None and initial is not None and not (
        np.allclose(pose[:3], initial[:3], atol=_SAME_POSE)
        and abs(abs(float(pose[3:] @ initial[3:])) - 1) < _SAME_POSE)
    if moved or (twist is not None and np.any(twist)):
        raise FeatureUnsupportedError(
            f"entity {name!r} is held by joints of its model: it can only be reset to its "
            "initial pose at rest, not teleported")


_QPOS_WIDTH = {mujoco.mjtJoint.mjJNT_FREE: 7, mujoco.mjtJoint.mjJNT_BALL: 4}
_QVEL_WIDTH = {mujoco.mjtJoint.mjJNT_FREE: 6, mujoco.mjtJoint.mjJNT_BALL: 3}


def reset_joints(m: mujoco.MjModel, d: mujoco.MjData, roots: np.ndarray) -> None:
    """Put every joint under these root bodies back to its initial value, at rest."""
    for j in np.flatnonzero(np.isin(m.body_rootid[m.jnt_bodyid], roots)):
        kind = int(m.jnt_type[j])
        qadr, vadr = m.jnt_qposadr[j], m.jnt_dofadr[j]
        width = _QPOS_WIDTH.get(kind, 1)
        d.qpos[qadr:qadr + width] = m.qpos0[qadr:qadr + width]
        d.qvel[vadr:vadr + _QVEL_WIDTH.get(kind, 1)] = 0.0


def place_static(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """Recompute the world poses of moved static bodies: with sleeping on, MuJoCo's
    kinematics skips static bodies (a moved one stayed where it was for collisions, rays
    and cameras); with it off for one pass, it computes every body."""
    flag = int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    sleeping = bool(m.opt.enableflags & flag)
    m.opt.enableflags &= ~flag
    try:
        mujoco.mj_kinematics(m, d)
    finally:
        if sleeping:
            m.opt.enableflags |= flag


def wake_all(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """Wake every sleeping tree, keeping the state; MuJoCo wakes none when a static body moves.

    mj_forward with sleeping switched off wakes all trees the way MuJoCo itself does
    (writing tree_asleep alone leaves its derived awake lists stale).
    """
    flag = int(mujoco.mjtEnableBit.mjENBL_SLEEP)
    if not m.opt.enableflags & flag or d.ntree_awake == m.ntree:
        return  # with sleeping off MuJoCo wakes every tree at the next step itself
    m.opt.enableflags &= ~flag
    mujoco.mj_forward(m, d)
    m.opt.enableflags |= flag


def read_states(m: mujoco.MjModel, d: mujoco.MjData, index: StateIndex,
                ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World-frame poses (n, 7) and twists (n, 6) of these bodies; fixed ones have no twist."""
    kind = index.kind[ids]
    poses = np.empty((len(ids), 7))
    twists = np.zeros((len(ids), 6))
    free = kind == FREE
    if free.any():
        q = d.qpos[index.qadr[ids[free]][:, None] + POSE]
        vel = d.qvel[index.vadr[ids[free]][:, None] + TWIST]
        poses[free, :3] = q[:, :3]
        poses[free, 3:] = to_xyzw(q[:, 3:])
        twists[free, :3] = vel[:, :3]
        twists[free, 3:] = rotate(q[:, 3:], vel[:, 3:])
    mocap = kind == MOCAP
    if mocap.any():
        mid = index.mocap[ids[mocap]]
        poses[mocap, :3] = d.mocap_pos[mid]
        poses[mocap, 3:] = to_xyzw(d.mocap_quat[mid])
    static = kind == STATIC
    if static.any():
        poses[static, :3] = m.body_pos[ids[static]]
        poses[static, 3:] = to_xyzw(m.body_quat[ids[static]])
    jointed = kind == JOINTED
    if jointed.any():
        poses[jointed], twists[jointed] = jointed_states(m, d, ids[jointed])
    return poses, twists


def write_free_poses(d: mujoco.MjData, index: StateIndex, ids: np.ndarray,
                     poses: np.ndarray) -> None:
    """Free bodies' world poses into qpos."""
    qadr = index.qadr[ids][:, None] + POSE
    d.qpos[qadr] = np.hstack([poses[:, :3], to_wxyz(poses[:, 3:])])


def write_mocap_poses(d: mujoco.MjData, index: StateIndex, ids: np.ndarray,
                      poses: np.ndarray) -> None:
    mid = index.mocap[ids]
    d.mocap_pos[mid] = poses[:, :3]
    d.mocap_quat[mid] = to_wxyz(poses[:, 3:])


def write_twists(d: mujoco.MjData, index: StateIndex, ids: np.ndarray, twists: np.ndarray,
                 poses: np.ndarray | None) -> None:
    """World-frame twists into free-joint qvel, whose angular part is in the body frame.

    The frame is the new pose's when one is given, else the body's current one.
    """
    quats = d.qpos[index.qadr[ids][:, None] + POSE[3:]] if poses is None \
        else to_wxyz(poses[:, 3:])
    local = rotate(quats, twists[:, 3:], inverse=True)
    d.qvel[index.vadr[ids][:, None] + TWIST] = np.hstack([twists[:, :3], local])


def first_geoms(m: mujoco.MjModel, ids: np.ndarray, spawned: np.ndarray) -> np.ndarray:
    """The first geom of each body: a spawned body's own, a model's lowest in its subtree;
    -1 where there is none."""
    first = np.where(m.body_geomnum[ids] > 0, m.body_geomadr[ids], -1)
    if spawned.all():
        return first
    roots = m.body_rootid[m.geom_bodyid]
    gids = np.flatnonzero(np.isin(roots, ids[~spawned]))
    lowest = np.full(m.nbody, m.ngeom)
    np.minimum.at(lowest, roots[gids], gids)
    found = lowest[ids[~spawned]]
    first[~spawned] = np.where(found < m.ngeom, found, -1)
    return first


# -- divergence ----------------------------------------------------------------------------
def _beyond(values: np.ndarray, limit: float) -> bool:
    """Whether any value's magnitude passes the limit (NaN counts as past it: a NaN max
    compares false)."""
    return not bool(np.abs(values).max(initial=0.0) <= limit)


def _finite(*arrays: np.ndarray) -> bool:
    """Whether every value is finite, in one dot product per array: NaN and infinity carry
    through it (a finite value past 1e154 overflows it, and is past every limit anyway)."""
    total = 0.0
    for values in arrays:
        flat = values.ravel()
        total += float(flat @ flat)
    return math.isfinite(total)


def within(d: mujoco.MjData, index: StateIndex, positions: np.ndarray, max_position: float,
           max_speed: float) -> bool:
    """Whether the state is finite, these qpos rows (the watched free bodies' x y z) and the
    jointed bodies' positions within ``max_position``, and every velocity component, angular
    ones in the world frame, within ``max_speed``.

    A free joint's angular velocity is kept in the body frame; no world component can pass
    its norm, so only the few rows whose norm passes the limit are rotated.
    """
    if not _finite(d.qpos, d.qvel, d.mocap_pos, d.mocap_quat):
        return False
    if _beyond(d.qpos[positions], max_position) or \
            _beyond(d.xpos[index.jointed], max_position) or \
            _beyond(d.qvel[index.other_dofs], max_speed):
        return False
    spin = d.qvel[index.spin_dofs]
    fast = np.linalg.norm(spin, axis=1) > max_speed
    if not fast.any():
        return True
    return not _beyond(rotate(d.qpos[index.spin_quats[fast]], spin[fast]), max_speed)
