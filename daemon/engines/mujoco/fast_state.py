"""A MuJoCo world's state kept in memory, for snapshots and restores of an unchanged
structure (``Engine.save_state``, daemon/world/states.py): the whole MjData (``mj_copyData``:
contacts, warm starts, sleep records, the lot, so the world goes on bit for bit as from the
moment it was kept), the few model arrays the engine edits between compiles (joint targets'
gains and damping, the sleep guard's sleep policies) and the engine's own records.

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

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# Model arrays the engine writes between compiles (joints.write_targets, Joints.write_law,
# sleep_guard.SleepGuard): kept with the state, put back with it.
EDITED_MODEL_ARRAYS = ("actuator_gainprm", "actuator_biasprm", "actuator_forcelimited",
                       "actuator_forcerange", "dof_damping", "tree_sleep_policy")
SPARES = 2  # dropped MjData kept for reuse, per layout
# Sizes that must agree for one model's MjData to fit another.
SIZES = ("nq", "nv", "nu", "na", "nbody", "ngeom", "nmocap", "ntree", "nconmax", "njmax")


# Dropped MjData by layout (every size of the model they were made for: equal sizes give
# equal layouts), for the next snapshot or clone of a model of that layout: allocating one
# maps its whole arena (63 MB for a 100-ball board) and faults it in as it is written,
# milliseconds; copying into a used one, microseconds. Only the physics thread uses it.
_SPARES: dict[tuple[int, ...], list[mujoco.MjData]] = {}


def layout(m: mujoco.MjModel) -> tuple[int, ...]:
    """Every size of a model (its integer fields n...): what an MjData's layout is made
    from. Reading them costs a quarter of a millisecond, so the last few models' are kept
    (by identity: forks share their source's model)."""
    for known, sizes in _LAYOUTS:
        if known is m:
            return sizes
    if not _SIZE_NAMES:
        _SIZE_NAMES.extend(name for name in dir(mujoco.MjModel) if name.startswith("n")
                           and isinstance(getattr(m, name), int))
    sizes = tuple(getattr(m, name) for name in _SIZE_NAMES)
    _LAYOUTS.insert(0, (m, sizes))
    del _LAYOUTS[KNOWN_LAYOUTS:]
    return sizes


_SIZE_NAMES: list[str] = []
KNOWN_LAYOUTS = 4  # models whose layout is kept (held alive: a few MB at most)
_LAYOUTS: list[tuple[mujoco.MjModel, tuple[int, ...]]] = []


def data_for(m: mujoco.MjModel) -> mujoco.MjData:
    """An MjData for ``m``: a dropped one of its layout, or a new one (its contents are
    to be overwritten whole, by mj_copyData)."""
    spares = _SPARES.get(layout(m))
    return spares.pop() if spares else mujoco.MjData(m)


def give_back(m: mujoco.MjModel, data: mujoco.MjData) -> None:
    """Keep an MjData nobody uses any more (made for ``m``'s layout, no thread pool)."""
    spares = _SPARES.setdefault(layout(m), [])
    if len(spares) < SPARES:
        spares.append(data)


@dataclass(frozen=True)
class MujocoState:
    """One moment of a MuJoCo world (see the module docstring)."""

    sizes: tuple[int, ...]
    layout: tuple[int, ...]
    data: mujoco.MjData
    model_arrays: dict[str, np.ndarray]
    records: dict[str, Any]
    nbytes: int


def _sizes(m: mujoco.MjModel) -> tuple[int, ...]:
    return tuple(int(getattr(m, s, 0)) for s in SIZES)


def save(engine: MujocoEngine) -> MujocoState | None:
    """The engine's state now (None for a broken world: it has none worth keeping)."""
    if engine.broken:
        return None
    m = engine.model
    data = data_for(m)
    mujoco.mj_copyData(data, m, engine.data)
    arrays = {name: getattr(m, name).copy() for name in EDITED_MODEL_ARRAYS}
    records = {"joints": engine.loaded_joints.copy(),
             "held": {n: w.copy() for n, w in engine.wrenches.held.items()},
             "balance": None if engine.sleep_guard is None else engine.sleep_guard.copy(),
             "looks": (engine.diverged, engine.crowded, engine.steps_since_look)}
    nbytes = int(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_INTEGRATION) * 8
                 + sum(a.nbytes for a in arrays.values()))
    return MujocoState(_sizes(m), layout(m), data, arrays, records, nbytes)


def load(engine: MujocoEngine, state: Any) -> bool:
    """Set the engine to ``state``; False (nothing changed) when it does not fit."""
    if not isinstance(state, MujocoState) or state.sizes != _sizes(engine.model):
        return False
    if engine.sharing is not None and not all(
            np.array_equal(getattr(engine.model, n), v) for n, v in state.model_arrays.items()):
        engine.own()  # its edited arrays differ from the state's: write into its own model
    m = engine.model
    if engine.sharing is None:  # (a shared model holds these values already)
        for name, values in state.model_arrays.items():
            getattr(m, name)[...] = values
    mujoco.mj_copyData(engine.data, m, state.data)
    records = state.records
    engine.loaded_joints = records["joints"].copy()
    engine.wrenches.held = {n: w.copy() for n, w in records["held"].items()}
    engine.sleep_guard = None if records["balance"] is None else records["balance"].copy()
    engine.diverged, engine.crowded, engine.steps_since_look = records["looks"]
    engine.broken = False
    engine.observed = None
    engine.start_workers()
    return True


def recycle(state: Any) -> None:
    """A dropped state's MjData serves the next snapshot or clone."""
    if isinstance(state, MujocoState):
        spares = _SPARES.setdefault(state.layout, [])
        if len(spares) < SPARES:
            spares.append(state.data)
