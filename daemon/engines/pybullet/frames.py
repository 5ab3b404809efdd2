"""Link frames in PyBullet: what the protocol calls a link's pose is its URDF frame, what
PyBullet keeps is its centre of mass (the inertial frame).

PyBullet's base and link states are those of the inertial frame; ``getLinkState`` also
gives the link frame's pose, but its linear velocity is the centre of mass's. The
protocol's twist is the velocity of the frame's origin: v_origin = v_com + w x (p_origin -
p_com). A model root with an inertial offset is converted both ways here (read, and set by
``set_states``); a root whose inertial frame is the identity needs nothing, and gets
nothing, so that its poses pass through untouched, bit for bit.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np
from pybullet_utils.bullet_client import BulletClient

Offset = tuple[np.ndarray, np.ndarray]  # inertial frame in the link frame: position, quat


def rotate(quats: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """Rotate each vector (n, 3) by its unit quaternion (n, 4, scalar last)."""
    xyz, w = quats[:, :3], quats[:, 3:4]
    t = 2.0 * np.cross(xyz, vectors)
    return vectors + w * t + np.cross(xyz, t)


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton products a * b of quaternions (n, 4, scalar last)."""
    av, aw, bv, bw = a[:, :3], a[:, 3:4], b[:, :3], b[:, 3:4]
    return np.hstack([aw * bv + bw * av + np.cross(av, bv),
                      aw * bw - np.sum(av * bv, axis=1, keepdims=True)])


def conjugate(quats: np.ndarray) -> np.ndarray:
    flipped: np.ndarray = quats * np.array([-1.0, -1.0, -1.0, 1.0])
    return flipped


def base_offset(bc: BulletClient, uid: int) -> Offset | None:
    """The base's inertial frame in its link frame, or None when it is the identity."""
    info = bc.getDynamicsInfo(uid, -1)
    position, orientation = np.array(info[3], float), np.array(info[4], float)
    if not position.any() and tuple(orientation) == (0.0, 0.0, 0.0, 1.0):
        return None
    return position, orientation


def com_to_frame(poses: np.ndarray, twists: np.ndarray, offsets: Sequence[Offset]) -> None:
    """Turn inertial-frame states (rows of poses and twists) into link-frame ones, in place:
    frame = com * inverse(offset)."""
    position = np.array([o[0] for o in offsets])
    inverse = conjugate(np.array([o[1] for o in offsets]))
    frame_q = multiply(poses[:, 3:], inverse)
    frame_p = poses[:, :3] - rotate(frame_q, position)
    twists[:, :3] += np.cross(twists[:, 3:], frame_p - poses[:, :3])
    poses[:, :3], poses[:, 3:] = frame_p, frame_q


def frame_to_com(poses: np.ndarray | None, twists: np.ndarray | None,
                 offsets: Sequence[Offset], orientations: np.ndarray) -> None:
    """The inverse of ``com_to_frame``, in place; ``orientations`` are the frames' (the
    poses' own, or the current ones when only twists are given)."""
    position = np.array([o[0] for o in offsets])
    arm = rotate(orientations, position)  # p_com - p_frame, world axes
    if twists is not None:
        twists[:, :3] += np.cross(twists[:, 3:], arm)
    if poses is not None:
        poses[:, :3] += arm
        poses[:, 3:] = multiply(poses[:, 3:], np.array([o[1] for o in offsets]))


def link_states(bc: BulletClient, uid: int, links: Sequence[int]
                ) -> tuple[np.ndarray, np.ndarray]:
    """Link-frame poses (n, 7) and twists of the origin (n, 6) of these links of a body."""
    states = bc.getLinkStates(uid, list(links), computeLinkVelocity=1,
                              computeForwardKinematics=1)
    n, flat = len(links), itertools.chain.from_iterable
    com = np.fromiter(flat(s[0] for s in states), float, 3 * n).reshape(n, 3)
    poses = np.fromiter(flat(itertools.chain(s[4], s[5]) for s in states), float,
                        7 * n).reshape(n, 7)
    twists = np.fromiter(flat(itertools.chain(s[6], s[7]) for s in states), float,
                         6 * n).reshape(n, 6)
    twists[:, :3] += np.cross(twists[:, 3:], poses[:, :3] - com)
    return poses, twists


def centres(bc: BulletClient, targets: Sequence[tuple[int, int]]) -> np.ndarray:
    """World centres of mass (n, 3) of bodies or links, given as (uid, link; -1: base)."""
    rows = [bc.getBasePositionAndOrientation(uid)[0] if link < 0
            else bc.getLinkState(uid, link, computeForwardKinematics=1)[0]
            for uid, link in targets]
    return np.array(rows, dtype=float).reshape(len(rows), 3)
