"""Reading and setting the entities' states, and the divergence check.

A spawned body's state is its free joint's six positions and velocities, converted for a
whole batch with numpy (frames.py). A model's root and links are read from their body
nodes' world frames; a model's root is set through its root joint (a free joint moves,
a welded root is placed).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import dartpy as dart
import numpy as np

from galton.daemon.engines.dart import frames
from galton.protocol.vocabulary import POSE_WIDTH, TWIST_WIDTH

if TYPE_CHECKING:
    from galton.daemon.engines.dart.spawn import Body


def free_state(bodies: Sequence[Body]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 6) free-joint positions and velocities of spawned bodies."""
    n = len(bodies)
    positions = np.array([b.skeleton.getPositions() for b in bodies], float).reshape(n, 6)
    velocities = np.array([b.skeleton.getVelocities() for b in bodies], float).reshape(n, 6)
    return positions, velocities


def read_poses(bodies: Sequence[Body]) -> np.ndarray:
    """(n, 7) poses alone, for a state stream: one DART call per spawned body (its free
    joint's positions), half of what ``read`` costs with the velocities."""
    spawned = [k for k, b in enumerate(bodies) if b.model is None]
    poses = np.zeros((len(bodies), POSE_WIDTH))
    if spawned:
        positions = np.concatenate([bodies[k].skeleton.getPositions() for k in spawned])
        positions = positions.reshape(len(spawned), 6)
        poses[spawned] = np.column_stack([positions[:, 3:],
                                          frames.rotvecs_to_quats(positions[:, :3])])
    for k, body in enumerate(bodies):
        if body.model is not None:
            poses[k] = node_state(body.node)[0]
    return poses


def read(bodies: Sequence[Body]) -> tuple[np.ndarray, np.ndarray]:
    """(n, 7) poses and (n, 6) world twists of these entities."""
    poses, twists = np.zeros((len(bodies), POSE_WIDTH)), np.zeros((len(bodies), TWIST_WIDTH))
    spawned = [k for k, b in enumerate(bodies) if b.model is None]
    if spawned:
        positions, velocities = free_state([bodies[k] for k in spawned])
        poses[spawned], twists[spawned] = frames.free_to_states(positions, velocities)
        fixed = [k for k in spawned if bodies[k].static]
        twists[fixed] = 0.0
    for k, body in enumerate(bodies):
        if body.model is not None:
            poses[k], twists[k] = node_state(body.node)
    return poses, twists


def node_state(node: Any) -> tuple[np.ndarray, np.ndarray]:
    """A body node's frame in the world: pose and twist."""
    matrix = np.asarray(node.getWorldTransform().matrix(), dtype=float)
    pose = np.concatenate([matrix[:3, 3], frames.matrix_to_quat(matrix[:3, :3])])
    twist = np.concatenate([np.asarray(node.getLinearVelocity(), dtype=float),
                            np.asarray(node.getAngularVelocity(), dtype=float)])
    return pose, twist


def write(bodies: Sequence[Body], poses: np.ndarray | None, twists: np.ndarray | None
          ) -> None:
    """Set poses and/or twists (None keeps that part, in the world frame; a twist alone
    leaves the free joint's positions untouched, so the pose stays bit for bit)."""
    if poses is None and twists is None:
        return
    spawned = [k for k, b in enumerate(bodies) if b.model is None]
    if spawned:
        _write_spawned([bodies[k] for k in spawned],
                       None if poses is None else np.asarray(poses, dtype=float)[spawned],
                       None if twists is None else np.asarray(twists, dtype=float)[spawned])
    others = [k for k, b in enumerate(bodies) if b.model is not None]
    if others:
        old_poses, old_twists = read([bodies[k] for k in others])
        for row, k in enumerate(others):
            place_root(bodies[k], old_poses[row] if poses is None else np.asarray(poses[k]),
                       old_twists[row] if twists is None else np.asarray(twists[k]))


def _write_spawned(bodies: Sequence[Body], poses: np.ndarray | None,
                   twists: np.ndarray | None) -> None:
    """Free-joint velocities are in the world frame: a pose alone keeps the twist as is."""
    positions = None if poses is None else frames.poses_to_free(poses)
    velocities = None if twists is None else frames.twists_to_free(twists)
    for row, body in enumerate(bodies):
        if positions is not None:
            body.skeleton.setPositions(positions[row])
        if velocities is not None and not body.static:
            body.skeleton.setVelocities(velocities[row])


def place_root(body: Body, pose: np.ndarray, twist: np.ndarray) -> None:
    """Move a model's root: its free joint to the pose and twist, a weld to the pose."""
    joint = body.skeleton.getRootJoint()
    transform = dart.math.Isometry3()
    transform.set_translation(pose[:3])
    transform.set_rotation(_rotation(pose[3:]))
    if joint.getType() == "FreeJoint":
        joint.setTransform(transform)
        joint.setLinearVelocity(twist[:3])
        joint.setAngularVelocity(twist[3:])
    else:
        joint.setTransformFromParentBodyNode(transform)


def _rotation(quat: np.ndarray) -> np.ndarray:
    matrix: np.ndarray = frames.rotations(frames.quats_to_rotvecs(quat.reshape(1, 4)))[0]
    return matrix


def moves(body: Body) -> bool:
    """A spawned moving body, or the root of a model that can move (a fixed base's links
    do)."""
    if body.model is None:
        return not body.static
    return body.name == body.model and bool(body.skeleton.isMobile())


def within(bodies: Sequence[Body], max_position: float, max_speed: float) -> bool:
    """Every moving entity finite, within ``max_position`` of the origin and below
    ``max_speed`` in every twist component."""
    moving = [b for b in bodies if moves(b)]
    spawned = [b for b in moving if b.model is None]
    if spawned:
        positions, velocities = free_state(spawned)
        if not (np.isfinite(positions).all() and np.isfinite(velocities).all()):
            return False
        poses, twists = frames.free_to_states(positions, velocities)
        if not (np.isfinite(twists).all() and np.abs(poses[:, :3]).max() <= max_position
                and np.abs(twists).max() <= max_speed):
            return False
    for root in (b for b in moving if b.model is not None):
        q, qdot = root.skeleton.getPositions(), root.skeleton.getVelocities()
        if not (np.isfinite(q).all() and np.isfinite(qdot).all()):
            return False
        for node in root.skeleton.getBodyNodes():
            pose, twist = node_state(node)
            if not (np.abs(pose[:3]).max() <= max_position and
                    np.abs(twist).max() <= max_speed):
                return False
    return True


SAFE_POSITION = 1e9  # m: ODE's hash space aborts the process on a body much further out


def safe_to_step(bodies: Sequence[Body]) -> bool:
    """Whether ODE's collision detector can take the world: every moving entity finite
    and within ``SAFE_POSITION`` of the origin. ODE asserts (and so aborts the whole
    daemon) on a NaN or astronomically far bounding box, so a world set to one is not
    stepped: it has diverged."""
    roots = [b for b in bodies if moves(b)]
    for body in roots:
        q, qdot = body.skeleton.getPositions(), body.skeleton.getVelocities()
        if not (np.isfinite(q).all() and np.isfinite(qdot).all()):
            return False
        if np.abs(body.node.getWorldTransform().translation()).max() > SAFE_POSITION:
            return False
    return True
