"""A MuJoCo world's state kept in memory, for snapshots and restores of an unchanged
structure (daemon/world/scene.py ``World.save_state``): the whole MjData (``mj_copyData``:
contacts, warm starts, sleep books, the lot, so the world goes on bit for bit as from the
moment it was kept), the few model arrays the engine edits between compiles (joint targets'
gains and damping, the balance guard's sleep policies) and the engine's own books.

No MJCF, no compile: tens of microseconds for a 100-ball board, where a portable snapshot
writes and compiles the spec. The state fits any engine whose compiled model has the same
sizes (the same world, or a clone of it); the World decides when the structure is the
same, and this refuses (False) only what it can see does not fit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco.joints import Joints

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# Model arrays the engine writes between compiles (joints.write_targets, Joints.write_law,
# balance.BalanceGuard): kept with the state, put back with it.
EDITED_MODEL_ARRAYS = ("actuator_gainprm", "actuator_biasprm", "actuator_forcelimited",
                       "actuator_forcerange", "dof_damping", "tree_sleep_policy")
SPARES = 2  # dropped MjData kept for reuse
# Sizes that must agree for one model's MjData to fit another.
SIZES = ("nq", "nv", "nu", "na", "nbody", "ngeom", "nmocap", "ntree", "nconmax", "njmax")


@dataclass(frozen=True)
class MujocoState:
    """One moment of a MuJoCo world (see the module docstring)."""

    sizes: tuple[int, ...]
    data: mujoco.MjData
    model_arrays: dict[str, np.ndarray]
    books: dict[str, Any]
    nbytes: int


def _sizes(m: mujoco.MjModel) -> tuple[int, ...]:
    return tuple(int(getattr(m, s, 0)) for s in SIZES)


def save(engine: MujocoEngine) -> MujocoState | None:
    """The engine's state now (None for a broken world: it has none worth keeping)."""
    if engine.broken:
        return None
    m = engine.model
    spares = engine.spare_datas
    data = spares.pop() if spares and spares[-1][0] == _sizes(m) else None
    data = data[1] if data is not None else mujoco.MjData(m)
    mujoco.mj_copyData(data, m, engine.data)
    arrays = {name: getattr(m, name).copy() for name in EDITED_MODEL_ARRAYS}
    books = {"joints": _copy_joints(engine.joint_book),
             "held": {n: w.copy() for n, w in engine.wrenches.held.items()},
             "balance": None if engine.balance is None else engine.balance.copy(),
             "looks": (engine.diverged, engine.crowded, engine.steps_since_look)}
    nbytes = int(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_INTEGRATION) * 8
                 + sum(a.nbytes for a in arrays.values()))
    return MujocoState(_sizes(m), data, arrays, books, nbytes)


def load(engine: MujocoEngine, state: Any) -> bool:
    """Set the engine to ``state``; False (nothing changed) when it does not fit."""
    if not isinstance(state, MujocoState) or state.sizes != _sizes(engine.model):
        return False
    m = engine.model
    for name, values in state.model_arrays.items():
        getattr(m, name)[...] = values
    mujoco.mj_copyData(engine.data, m, state.data)
    books = state.books
    engine.joint_book = _copy_joints(books["joints"])
    engine.wrenches.held = {n: w.copy() for n, w in books["held"].items()}
    engine.balance = None if books["balance"] is None else books["balance"].copy()
    engine.diverged, engine.crowded, engine.steps_since_look = books["looks"]
    engine.broken = False
    engine.observed = None
    engine.start_workers()
    return True


def recycle(engine: MujocoEngine, state: Any) -> None:
    """Keep a dropped state's MjData for the next ``save`` (allocating one costs its whole
    arena, milliseconds for a 100-ball board; copying into one, microseconds)."""
    if isinstance(state, MujocoState) and state.sizes == _sizes(engine.model) \
            and state.data.narena == engine.data.narena:
        engine.spare_datas[:] = [*engine.spare_datas[-(SPARES - 1):], (state.sizes,
                                                                      state.data)]


def _copy_joints(source: Joints) -> Joints:
    joints = Joints()
    joints.infos = {root: list(infos) for root, infos in source.infos.items()}
    joints.targets = dict(source.targets)  # Target is frozen
    joints.slot = dict(source.slot)
    joints.qadr, joints.vadr = source.qadr.copy(), source.vadr.copy()
    joints.own, joints.own_damping = dict(source.own), source.own_damping.copy()
    joints.target_damping = source.target_damping.copy()
    return joints
