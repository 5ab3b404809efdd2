"""The numbers of a compiled MuJoCo world, exactly, as plain data: for ``snapshot``.

MuJoCo writes a spec as XML with six significant digits, so the XML of a snapshot carries
the world's structure and the numbers travel beside it, bit for bit:

- the compiled model's float64 arrays and its statistics (``stat``): some were written into
  the model alone (a pool-bound body's pose, a parked body's gravity compensation), and a
  fresh compile would round the rest;
- the data: MuJoCo's integration state (``mj_getState``: time, qpos, qvel, act, warm start,
  ctrl, applied forces, mocap poses...), every other float64 array that is not rebuilt
  from scratch in each step (a sleeping tree's positions, inertias and forces are kept from
  the step it fell asleep in, not recomputed), and the sleep records (which trees sleep, in
  which cycles, and the awake lists MuJoCo derives from them).

Arrays travel as ``{"dtype", "shape", "data"}`` with ``data`` the little-endian bytes. Only
float arrays are taken from a snapshot as they come: the few integer ones (the sleep records)
index other arrays, so each is checked against the model before MuJoCo reads it.
"""

from __future__ import annotations

from typing import Any

import mujoco
import numpy as np

from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

F64, F32, I32 = np.dtype("<f8"), np.dtype("<f4"), np.dtype("<i4")
# Single-precision model arrays that come from asset files (meshes...): compiled alike.
FILE_PREFIXES = ("mesh_", "skin_", "flex_", "hfield_")
# Double ones from the files alone, and the bounding volumes, of which only the bodies'
# travel (a mesh's thousands of nodes are compiled alike from its file).
FROM_FILES = ("mesh_polynormal", "bvh_aabb")
STAT_FIELDS = ("meaninertia", "meanmass", "meansize", "extent", "center")
# Data arrays in MuJoCo's arena: made anew by every step (contacts, constraints, islands).
ARENA_PREFIXES = ("efc_", "efm_", "iefc_", "island_", "map_", "contact", "iacc", "ifrc")
STATE = mujoco.mjtState.mjSTATE_INTEGRATION
# The sleep records: per tree, per body (flags), and the awake lists with their lengths.
SLEEP_FLAGS = ("tree_awake", "body_awake")
AWAKE_LISTS = {"body_awake_ind": ("nbody_awake", "nbody"),
               "parent_awake_ind": ("nparent_awake", "nbody"),
               "dof_awake_ind": ("nv_awake", "nv")}
_SLEEP_STATES = frozenset(int(s) for s in mujoco.mjtSleepState.__members__.values())


# -- arrays as plain data ---------------------------------------------------------------
def pack(array: np.ndarray, dtype: np.dtype[Any] = F64) -> dict[str, Any]:
    a = np.ascontiguousarray(array, dtype=dtype)
    return {"dtype": dtype.str, "shape": list(a.shape), "data": a.tobytes()}


def unpack(obj: Any, where: str, dtype: np.dtype[Any], shape: tuple[int, ...]) -> np.ndarray:
    """An array of this dtype and shape from plain data, or InvalidArgumentError."""
    if not isinstance(obj, dict) or set(obj) != {"dtype", "shape", "data"}:
        raise InvalidArgumentError(f"{where} must be an array {{dtype, shape, data}}, got "
                                   f"{brief(obj)}")
    if obj["dtype"] != dtype.str:
        raise InvalidArgumentError(f"{where} must be of dtype {dtype.str!r}, got "
                                   f"{brief(obj['dtype'])}")
    if obj["shape"] != list(shape):
        raise InvalidArgumentError(f"{where} must have shape {list(shape)} (this world's), "
                                   f"got {brief(obj['shape'])}")
    data = obj["data"]
    if not isinstance(data, bytes | bytearray) or len(data) != dtype.itemsize * \
            int(np.prod(shape)):
        raise InvalidArgumentError(f"{where} must be {dtype.itemsize * int(np.prod(shape))} "
                                   f"bytes, got {brief(data)}")
    return np.frombuffer(bytes(data), dtype=dtype).reshape(shape)


def names_map(obj: Any, where: str) -> dict[str, Any]:
    if not isinstance(obj, dict) or not all(isinstance(k, str) for k in obj):
        raise InvalidArgumentError(f"{where} must be a map of names, got {brief(obj)}")
    return obj


def _float_arrays(struct: Any, prefixes: tuple[str, ...] = (),
                  dtype: np.dtype[Any] = F64) -> dict[str, np.ndarray]:
    """The arrays of an MjModel or MjData of this dtype by name (but those whose names
    begin with these prefixes)."""
    out = {}
    for name in dir(struct):
        if name.startswith("_") or name.startswith(prefixes):
            continue
        value = getattr(struct, name, None)
        if isinstance(value, np.ndarray) and value.dtype == dtype:
            out[name] = value
    return out


def _write_all(targets: dict[str, np.ndarray], obj: Any, where: str,
               dtype: np.dtype[Any] = F64) -> None:
    """Every target array from plain data: all of them, nothing more, each its own shape;
    all checked before any is written."""
    table = names_map(obj, where)
    if set(table) != set(targets):
        missing, extra = sorted(set(targets) - set(table)), sorted(set(table) - set(targets))
        raise InvalidArgumentError(f"{where} must hold this world's arrays: missing "
                                   f"{missing[:5]}, unknown {extra[:5]}")
    values = {n: unpack(table[n], f"{where}.{n}", dtype, a.shape) for n, a in targets.items()}
    for name, value in values.items():
        targets[name][...] = value


# -- the model ---------------------------------------------------------------------------
def model_numbers(m: mujoco.MjModel) -> dict[str, Any]:
    return {"arrays": {n: pack(a) for n, a in _float_arrays(m, FROM_FILES).items()},
            "bvh": pack(m.bvh_aabb[_body_nodes(m)]),
            "arrays32": {n: pack(a, F32) for n, a in
                         _float_arrays(m, FILE_PREFIXES, F32).items()},
            "stat": {f: pack(np.atleast_1d(getattr(m.stat, f))) for f in STAT_FIELDS}}


def write_model_numbers(m: mujoco.MjModel, obj: Any) -> None:
    table = names_map(obj, "snapshot.model")
    stat = names_map(table.get("stat"), "snapshot.model.stat")
    values = {f: unpack(stat.get(f), f"snapshot.model.stat.{f}", F64,
                        np.atleast_1d(getattr(m.stat, f)).shape) for f in STAT_FIELDS}
    nodes = _body_nodes(m)
    bvh = unpack(table.get("bvh"), "snapshot.model.bvh", F64, (len(nodes), 6))
    _write_all(_float_arrays(m, FROM_FILES), table.get("arrays"), "snapshot.model.arrays")
    _write_all(_float_arrays(m, FILE_PREFIXES, F32), table.get("arrays32"),
               "snapshot.model.arrays32", F32)
    m.bvh_aabb[nodes] = bvh
    for field, value in values.items():
        setattr(m.stat, field, value if field == "center" else float(value[0]))


def _body_nodes(m: mujoco.MjModel) -> np.ndarray:
    """The rows of the bodies' bounding volume nodes in ``bvh_aabb``."""
    has = m.body_bvhnum > 0
    count, first = m.body_bvhnum[has], m.body_bvhadr[has]
    starts = np.repeat(first - (np.cumsum(count) - count), count)
    return np.asarray(starts + np.arange(int(count.sum())), dtype=np.int64)


# -- the data ----------------------------------------------------------------------------
def _data_arrays(d: mujoco.MjData) -> dict[str, np.ndarray]:
    return _float_arrays(d, ARENA_PREFIXES)


def data_numbers(m: mujoco.MjModel, d: mujoco.MjData) -> dict[str, Any]:
    state = np.empty(mujoco.mj_stateSize(m, STATE))
    mujoco.mj_getState(m, d, state, STATE)
    sleep = {n: pack(getattr(d, n), I32) for n in ("tree_asleep", *SLEEP_FLAGS, *AWAKE_LISTS)}
    counts = {count: int(getattr(d, count)) for count, _ in AWAKE_LISTS.values()}
    counts["ntree_awake"] = int(d.ntree_awake)
    return {"state": pack(state), "arrays": {n: pack(a) for n, a in _data_arrays(d).items()},
            "sleep": sleep, "counts": counts}


def write_data_numbers(m: mujoco.MjModel, d: mujoco.MjData, obj: Any) -> None:
    """A fresh MjData of the same model made the snapshot's, checked before any write."""
    table = names_map(obj, "snapshot.data")
    state = unpack(table.get("state"), "snapshot.data.state", F64,
                   (mujoco.mj_stateSize(m, STATE),))
    sleep, counts = _sleep_records(m, d, table)
    _write_all(_data_arrays(d), table.get("arrays"), "snapshot.data.arrays")
    mujoco.mj_setState(m, d, state, STATE)
    for name, value in sleep.items():
        getattr(d, name)[...] = value
    for name, count in counts.items():
        setattr(d, name, count)


def _sleep_records(m: mujoco.MjModel, d: mujoco.MjData,
                 table: dict[str, Any]) -> tuple[dict[str, np.ndarray], dict[str, int]]:
    """The sleep records, checked: flags are sleep states, awake lists hold valid ids, and
    the sleeping trees' cycles are cycles of sleeping trees."""
    records = names_map(table.get("sleep"), "snapshot.data.sleep")
    raw = names_map(table.get("counts"), "snapshot.data.counts")
    sleep = {n: unpack(records.get(n), f"snapshot.data.sleep.{n}", I32, getattr(d, n).shape)
             for n in ("tree_asleep", *SLEEP_FLAGS, *AWAKE_LISTS)}
    counts = {"ntree_awake": _count(raw, "ntree_awake", m.ntree)}
    for name, (count, size) in AWAKE_LISTS.items():
        counts[count] = _count(raw, count, getattr(m, size))
        listed = sleep[name][:counts[count]]
        if ((listed < 0) | (listed >= getattr(m, size))).any():
            raise InvalidArgumentError(f"snapshot.data.sleep.{name} holds ids outside "
                                       f"0..{getattr(m, size) - 1}")
    for name in SLEEP_FLAGS:
        if not set(np.unique(sleep[name]).tolist()) <= _SLEEP_STATES:
            raise InvalidArgumentError(f"snapshot.data.sleep.{name} holds values that are "
                                       "no sleep state")
    _check_cycles(sleep["tree_asleep"], m.ntree)
    return sleep, counts


def _count(raw: dict[str, Any], name: str, most: int) -> int:
    value = raw.get(name)
    if type(value) is not int or not 0 <= value <= most:
        raise InvalidArgumentError(f"snapshot.data.counts.{name} must be an int in "
                                   f"0..{most}, got {brief(value)}")
    return value


def _check_cycles(asleep: np.ndarray, ntree: int) -> None:
    """A sleeping tree names the next tree of its island (a cycle); awake ones are < 0."""
    sleeping = np.flatnonzero(asleep >= 0)
    following = asleep[sleeping]
    if (following >= ntree).any() or (asleep[np.minimum(following, ntree - 1)] < 0).any() \
            or len(np.unique(following)) != len(following):
        raise InvalidArgumentError("snapshot.data.sleep.tree_asleep is not a set of cycles "
                                   f"of sleeping trees among the world's {ntree}")
