"""The MuJoCo engine's pose reader for state streams: where the streamed bodies' poses live
is worked out once, and a read of 1,000 free bodies is then one gather from qpos.

A stream reads the same names up to 60 times a second on the physics thread, where
``get_states`` would look every name up, sort bodies by kind and compute twists each time
(about one step of a 1,000-sphere world per read: docs/PERFORMANCE.md, "State streams").
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.mujoco import state as mst

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# A free joint's qpos columns in the wire's order: x y z, then the quaternion's x y z w
# (MuJoCo keeps w x y z).
FREE_POSE_COLUMNS = np.array([0, 1, 2, 4, 5, 6, 3])


class PoseReader:
    """Reads the poses (n, 7) of fixed names: one gather per kind of body (free bodies from
    qpos, mocap bodies from mocap_pos/quat, static ones from the model), jointed links as
    get_states reads them. Works out the rows again whenever the engine compiled a new
    model since the last read."""

    def __init__(self, engine: MujocoEngine, names: Sequence[str]) -> None:
        self.engine = engine
        self.ids = engine._body_ids(names)
        self.index: mst.StateIndex | None = None
        # Positions in ``names`` of each kind of body, and where their poses live.
        self.at: dict[int, np.ndarray] = {}
        self.rows = np.empty((0, 7), dtype=np.int64)  # the free bodies' qpos rows
        self.mocap = np.empty(0, dtype=np.int64)

    def __call__(self) -> np.ndarray:
        engine = self.engine
        if self.index is not engine._index:
            self._locate(engine._index)
        m, d, at = engine._model, engine._data, self.at
        poses = np.empty((len(self.ids), 7))
        poses[at[mst.FREE]] = d.qpos[self.rows]
        if len(at[mst.STATIC]):
            ids = self.ids[at[mst.STATIC]]
            poses[at[mst.STATIC]] = np.hstack([m.body_pos[ids], mst.to_xyzw(m.body_quat[ids])])
        if len(self.mocap):
            poses[at[mst.MOCAP]] = np.hstack([d.mocap_pos[self.mocap],
                                              mst.to_xyzw(d.mocap_quat[self.mocap])])
        if len(at[mst.JOINTED]):
            poses[at[mst.JOINTED]] = mst.read_states(m, d, engine._index,
                                                     self.ids[at[mst.JOINTED]])[0]
        return poses

    def _locate(self, index: mst.StateIndex) -> None:
        self.index = index
        kind = index.kind[self.ids]
        self.at = {k: np.flatnonzero(kind == k)
                   for k in (mst.FREE, mst.MOCAP, mst.JOINTED, mst.STATIC)}
        self.rows = index.qadr[self.ids[self.at[mst.FREE]]][:, None] + FREE_POSE_COLUMNS
        self.mocap = index.mocap[self.ids[self.at[mst.MOCAP]]]
