"""Teleporting entities of the MuJoCo world (``set_states``), as functions of the engine.

Free bodies are written into qpos/qvel, mocap ones into the data's mocap poses, static ones
into the compiled model and the spec; a body held by joints (a model root jointed to the
world) can only be put back where it was loaded, at rest. The World passes only spawned
bodies and model roots: links move with their joints (``set_joint_states``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.mujoco import state as mst
from galton.daemon.engines.mujoco.state import FREE, JOINTED, MOCAP, STATIC
from galton.protocol import InvalidArgumentError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def set_states(engine: MujocoEngine, names: Sequence[str], poses: np.ndarray | None,
               twists: np.ndarray | None) -> None:
    """Teleport bodies and/or set their world twists (see the module docstring)."""
    ids = engine._body_ids(names)
    kind = engine._index.kind[ids]
    free, mocap, jointed = kind == FREE, kind == MOCAP, kind == JOINTED
    static = kind == STATIC
    poses = None if poses is None else np.asarray(poses, dtype=float)
    twists = None if twists is None else np.asarray(twists, dtype=float)
    fixed = mocap | static
    if twists is not None and np.any(twists[fixed]):
        bad = names[int(np.flatnonzero(fixed & np.any(twists, axis=1))[0])]
        raise InvalidArgumentError(f"entity {bad!r} is static: it cannot be given a "
                                   "non-zero twist")
    for row in np.flatnonzero(jointed).tolist():
        mst.check_jointed(names[row], engine._entities[names[row]].initial_pose,
                          None if poses is None else poses[row],
                          None if twists is None else twists[row])
    d = engine._data
    if poses is not None and twists is None and free.any():
        # A pose alone keeps the world-frame twist: MuJoCo holds a free body's spin in
        # its own frame, so it is read first and written back after the turn.
        twists = np.zeros((len(ids), 6))
        twists[free] = mst.read_states(engine._model, d, engine._index, ids[free])[1]
    if poses is not None and free.any():
        mst.write_free_poses(d, engine._index, ids[free], poses[free])
    if twists is not None and free.any():
        mst.write_twists(d, engine._index, ids[free], twists[free],
                         None if poses is None else poses[free])
    if poses is not None and mocap.any():
        mst.write_mocap_poses(d, engine._index, ids[mocap], poses[mocap])
    if poses is not None and static.any():
        move_static(engine, [names[i] for i in np.flatnonzero(static).tolist()], ids[static],
                    poses[static])
    if poses is not None and fixed.any():
        mst.wake_all(engine._model, d)
    if poses is not None and static.any():
        mst.place_static(engine._model, d)
    if jointed.any():
        mst.reset_joints(engine._model, d, ids[jointed])


def move_static(engine: MujocoEngine, names: Sequence[str], ids: np.ndarray,
                poses: np.ndarray) -> None:
    """Pose static bodies in the compiled model and in the spec (kept by recompiles)."""
    engine._xml = None
    quats = mst.to_wxyz(poses[:, 3:])
    engine._model.body_pos[ids] = poses[:, :3]
    engine._model.body_quat[ids] = quats
    for row, name in enumerate(names):
        body = engine._entities[name].body
        body.pos = poses[row, :3]
        body.quat = quats[row]
