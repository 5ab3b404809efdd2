"""Snapshots of the MuJoCo world as plain data, and restoring one on a fresh engine.

A snapshot holds the world's spec as MJCF (its structure: bodies in their order, frames,
geoms, joints, actuators, loaded models' assets -- meshes by file name), the compiled
model's and the data's numbers exactly (``mujoco_snapshot_arrays``: XML keeps six digits),
the parameters, and the engine's own books: entities, the pool of parked bodies, loaded
models' joints and held targets, held wrenches, the balance guard, and the counters of the
periodic looks. Restoring parses the MJCF, compiles it, writes the exact numbers into the
model, writes them back into the spec (``MjSpec.copy_back``: later recompiles start from
the same values as the source's) and into a fresh MjData, then rebuilds the books.

The promise (``MujocoEngine.snapshot``): a world restored from a snapshot of world A, and A
itself, given the same requests afterwards, give the same states bit for bit. A mesh named
by file in the MJCF must still be there at restore (the daemon makes models' file names
absolute; the snapshot holds the names, not the files).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines import mujoco_snapshot_arrays as arrays
from galton.daemon.engines import mujoco_spec as ms
from galton.daemon.engines.mujoco_entity import (
    ASSET_KINDS,
    HOME,
    MUJOCO_ERRORS,
    Assets,
    Entity,
)
from galton.daemon.engines.mujoco_joints import Target
from galton.daemon.engines.mujoco_rig import body_name
from galton.daemon.params import check_updates
from galton.protocol import (
    TARGET_MODES,
    GaltonError,
    InvalidArgumentError,
    JointInfo,
    OperationFailedError,
)
from galton.protocol.errors import brief

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco_engine import MujocoEngine

FORMAT = 1
ENGINE = "mujoco"
SIZES = ("nbody", "ngeom", "njnt", "nq", "nv", "nu", "ntree", "nmocap")
SOURCES = ("spawn", "model", "link")
KEYS = frozenset({"format", "engine", "engine_version", "params", "spec", "memory", "sizes",
                  "model", "data", "entities", "loads", "kinds", "pool", "joints", "targets",
                  "wrenches", "balance", "looks"})


# -- taking a snapshot ----------------------------------------------------------------------
def snapshot(engine: MujocoEngine) -> dict[str, Any]:
    if engine._broken:
        raise OperationFailedError("the MuJoCo world is broken (a failed step or delete); "
                                   "reset it before taking a snapshot")
    if engine._pool_edited:
        _recompile(engine)
    m, d = engine._model, engine._data
    loads: dict[int, int] = {}  # id(Assets) -> its place in "loads"
    kinds: dict[tuple[Any, ...], int] = {}  # pool kind -> its place in "kinds"
    entities = [_entity(name, e, loads, kinds) for name, e in engine._entities.items()]
    parked = [[kinds.setdefault(key, len(kinds)), [b.name for b in bodies]]
              for key, bodies in engine._pool._parked.items()]
    assets = {id(e.assets): e.assets for e in engine._entities.values() if e.assets}
    return {
        "format": FORMAT, "engine": ENGINE, "engine_version": mujoco.__version__,
        "params": engine.get_params(), "spec": _xml(engine),
        "memory": int(engine._spec.memory), "sizes": {s: int(getattr(m, s)) for s in SIZES},
        "model": arrays.model_numbers(m), "data": arrays.data_numbers(m, d),
        "entities": entities,
        "loads": [{"assets": sorted([k, n] for k, n in assets[i].names),
                   "roots": assets[i].roots} for i in sorted(loads, key=loads.__getitem__)],
        "kinds": [_key(key) for key in kinds],
        "pool": {"serial": engine._pool._serial, "parked": parked},
        "joints": {root: [i.to_wire() for i in infos]
                   for root, infos in engine._joints.infos.items()},
        "targets": {n: [t.mode, t.target, t.kp, t.kd, t.max_effort]
                    for n, t in engine._joints.targets.items()},
        "wrenches": {n: arrays.pack(w) for n, w in engine._wrenches.held.items()},
        "balance": None if engine._balance is None else engine._balance.books(),
        "looks": {"diverged": engine._diverged, "crowded": engine._crowded,
                  "steps_since_look": engine._steps_since_look},
    }


def _xml(engine: MujocoEngine) -> str:
    """The spec as MJCF: 50 ms for a 500-ball board, so kept until the spec changes (a
    compile, a parameter, an update, a static body moved; pool edits recompile first)."""
    if engine._xml is None:
        engine._xml = engine._spec.to_xml()
    return engine._xml


def _recompile(engine: MujocoEngine) -> None:
    """Compile the model as its spec compiles it, as a restore will: binding and parking
    bodies in the pool edit the compiled model alone (collisions, hence its bounding volume
    hierarchy). The bodies stay where they are in the model, so the whole data, sleep books
    included, and the balance guard's books are carried over exactly."""
    numbers = arrays.data_numbers(engine._model, engine._data)
    guard = None if engine._balance is None else engine._balance.books()
    engine._recompile()
    arrays.write_data_numbers(engine._model, engine._data, numbers)
    if guard is not None and engine._balance is not None:
        engine._balance.load(engine._model, guard)


def _entity(name: str, e: Entity, loads: dict[int, int],
            kinds: dict[tuple[Any, ...], int]) -> dict[str, Any]:
    load = None if e.assets is None else loads.setdefault(id(e.assets), len(loads))
    kind = None if e.key is None else kinds.setdefault(e.key, len(kinds))
    return {"name": name, "body": e.body.name, "static": e.static, "source": e.source,
            "friction": e.friction, "restitution": e.restitution,
            "initial_pose": None if e.initial_pose is None else [float(v) for v in
                                                                 e.initial_pose],
            "kind": kind, "parts": list(e.parts),
            "model": e.model, "load": load}


def _key(key: tuple[Any, ...]) -> list[Any]:
    """A pool kind (mujoco_pool.key_of) as plain data."""
    shape, size, static, material = key
    return [shape, list(size), static, {
        "friction": material.friction, "spin": list(material.spin),
        "condim": material.condim, "solref": list(material.solref),
        "solimp": list(material.solimp),
        "rgba": None if material.rgba is None else list(material.rgba),
        "mass": material.mass}]


# -- restoring -----------------------------------------------------------------------------
def restore(engine: MujocoEngine, data: Any) -> None:
    """Rebuild the snapshot's world on this fresh engine; InvalidArgumentError for anything
    malformed (the engine is then to be discarded)."""
    _check_header(data)
    values = _params(data["params"])
    spec = _parse(data["spec"], data["memory"], values)
    try:
        model = spec.compile()
    except MUJOCO_ERRORS as exc:
        raise InvalidArgumentError(f"snapshot.spec does not compile: {exc}") from exc
    _check_sizes(model, data["sizes"])
    arrays.write_model_numbers(model, data["model"])
    try:
        spec.copy_back(model)
    except MUJOCO_ERRORS as exc:
        raise InvalidArgumentError(f"snapshot.model does not fit its spec: {exc}") from exc
    state = mujoco.MjData(model)
    arrays.write_data_numbers(model, state, data["data"])
    home = spec.frame(HOME)
    if home is None:
        raise InvalidArgumentError(f"snapshot.spec has no frame {HOME!r}")
    engine._values, engine._spec, engine._home = values, spec, home
    engine._model, engine._data, engine._litter = model, state, []
    engine._xml = data["spec"]  # compiles to this world as well as its own MJCF would
    _books(engine, data)
    engine._workers = 0
    engine._start_workers()


def _check_header(data: Any) -> None:
    if not isinstance(data, dict):
        raise InvalidArgumentError(f"a MuJoCo snapshot must be a map, got {brief(data)}")
    if data.get("engine") != ENGINE:
        raise InvalidArgumentError(f"the snapshot is of the {brief(data.get('engine'))} "
                                   f"engine, not of {ENGINE}")
    if data.get("format") != FORMAT:
        raise InvalidArgumentError(f"the MuJoCo snapshot is of format "
                                   f"{brief(data.get('format'))}; this engine reads {FORMAT}")
    if data.get("engine_version") != mujoco.__version__:
        raise InvalidArgumentError(
            f"the snapshot was taken with MuJoCo {brief(data.get('engine_version'))}; this "
            f"is {mujoco.__version__}, whose steps need not be the same bit for bit")
    if set(data) != KEYS:
        raise InvalidArgumentError(f"a MuJoCo snapshot holds {sorted(KEYS)}: missing "
                                   f"{sorted(KEYS - set(data))}, unknown "
                                   f"{sorted(set(data) - KEYS)[:5]}")


def _params(params: Any) -> dict[str, Any]:
    if not isinstance(params, dict) or set(params) != set(ms.PARAMS):
        raise InvalidArgumentError(f"snapshot.params must give every MuJoCo parameter, got "
                                   f"{brief(params)}")
    return {**{n: p.default for n, p in ms.PARAMS.items()},
            **check_updates(ENGINE, ms.PARAMS, params)}


def _parse(xml: Any, memory: Any, values: dict[str, Any]) -> mujoco.MjSpec:
    if not isinstance(xml, str):
        raise InvalidArgumentError(f"snapshot.spec must be MJCF text, got {brief(xml)}")
    if type(memory) is not int or not 0 < memory <= ms.ARENA_CAP:
        raise InvalidArgumentError(f"snapshot.memory must be an int in 1..{ms.ARENA_CAP}, "
                                   f"got {brief(memory)}")
    try:
        spec = mujoco.MjSpec.from_string(xml)
    except MUJOCO_ERRORS as exc:
        raise InvalidArgumentError(f"snapshot.spec is not MJCF MuJoCo reads: {exc}") from exc
    spec.copy_during_attach = True
    spec.memory = memory
    ms.write_options(spec.option, values)
    return spec


def _check_sizes(model: mujoco.MjModel, sizes: Any) -> None:
    made = {s: int(getattr(model, s)) for s in SIZES}
    if sizes != made:
        raise InvalidArgumentError(f"snapshot.spec compiles to a world of {made}, not of its "
                                   f"sizes {brief(sizes)}")


# -- the engine's books ----------------------------------------------------------------------
def _books(engine: MujocoEngine, data: dict[str, Any]) -> None:
    loads = [_load(i, load) for i, load in enumerate(_list(data["loads"], "loads"))]
    kinds = [_read_key(kind) for kind in _list(data["kinds"], "kinds")]
    engine._entities = {}
    for row in _list(data["entities"], "entities"):
        name, entity = _read_entity(engine._spec, row, loads, kinds)
        engine._entities[name] = entity
    engine._parts = {n for n, e in engine._entities.items() if e.source == "link"}
    engine._models = sum(e.source == "model" for e in engine._entities.values())
    _pool(engine, data["pool"], kinds)
    _joints(engine, data["joints"], data["targets"])
    _wrenches(engine, data["wrenches"])
    looks = data["looks"]
    if not isinstance(looks, dict) or set(looks) != {"diverged", "crowded",
                                                     "steps_since_look"} or \
            not isinstance(looks["diverged"], bool) or not isinstance(looks["crowded"], bool):
        raise InvalidArgumentError(f"snapshot.looks is malformed: {brief(looks)}")
    steps = looks["steps_since_look"]
    if type(steps) is not int or not 0 <= steps < 1 << 31:
        raise InvalidArgumentError(f"snapshot.looks.steps_since_look is {brief(steps)}")
    engine._diverged, engine._crowded = looks["diverged"], looks["crowded"]
    engine._steps_since_look = steps
    try:
        engine._reindex()  # writes the held targets and wrenches into the model and data
    except InvalidArgumentError:
        raise
    except (GaltonError, KeyError, IndexError) as exc:
        raise InvalidArgumentError(f"snapshot names what its world lacks: {exc}") from exc
    balance = data["balance"]
    if (balance is None) != (engine._balance is None):
        raise InvalidArgumentError("snapshot.balance must be given exactly when "
                                   "mujoco.wake_balanced is on")
    if engine._balance is not None:
        engine._balance.load(engine._model, balance)


def _list(value: Any, where: str) -> list[Any]:
    if not isinstance(value, list):
        raise InvalidArgumentError(f"snapshot.{where} must be a list, got {brief(value)}")
    return value


def _fields(row: Any, keys: set[str], where: str) -> dict[str, Any]:
    if not isinstance(row, dict) or set(row) != keys:
        raise InvalidArgumentError(f"snapshot.{where} must be a map of {sorted(keys)}, got "
                                   f"{brief(row)}")
    return row


def _load(i: int, row: Any) -> Assets:
    row = _fields(row, {"assets", "roots"}, f"loads[{i}]")
    names = _list(row["assets"], f"loads[{i}].assets")
    if not all(isinstance(p, list) and len(p) == 2 and p[0] in ASSET_KINDS and
               isinstance(p[1], str) for p in names) or type(row["roots"]) is not int:
        raise InvalidArgumentError(f"snapshot.loads[{i}] is malformed")
    return Assets({(p[0], p[1]) for p in names}, row["roots"])


ENTITY_KEYS = {"name", "body", "static", "source", "friction", "restitution", "initial_pose",
               "kind", "parts", "model", "load"}


def _read_entity(spec: mujoco.MjSpec, row: Any, loads: list[Assets],
                 kinds: list[tuple[Any, ...]]) -> tuple[str, Entity]:
    row = _fields(row, ENTITY_KEYS, "entities[]")
    name, source = row["name"], row["source"]
    if not isinstance(name, str) or source not in SOURCES or \
            not isinstance(row["static"], bool) or not isinstance(row["body"], str):
        raise InvalidArgumentError(f"snapshot.entities holds a malformed entity {brief(row)}")
    expected = name if source == "spawn" else body_name(name)
    body = spec.body(row["body"]) if row["body"] == expected else None
    if body is None:
        raise InvalidArgumentError(f"snapshot.entities: {name!r} has no body in the spec")
    load, kind = row["load"], row["kind"]
    if load is not None:
        _index(load, len(loads), f"entities[{name!r}].load")
    if kind is not None:
        _index(kind, len(kinds), f"entities[{name!r}].kind")
    parts = _list(row["parts"], "entities[].parts")
    if not all(isinstance(p, str) for p in parts) or not isinstance(row["model"],
                                                                    str | None):
        raise InvalidArgumentError(f"snapshot.entities: {name!r} has malformed parts")
    return name, Entity(
        body, row["static"], source=source, friction=_number(row["friction"], name),
        restitution=_number(row["restitution"], name),
        initial_pose=None if row["initial_pose"] is None else _floats(row["initial_pose"], 7),
        key=None if kind is None else kinds[kind], parts=tuple(parts),
        model=row["model"], assets=None if load is None else loads[load])


def _index(value: Any, size: int, where: str) -> int:
    if type(value) is not int or not 0 <= value < size:
        raise InvalidArgumentError(f"snapshot.{where} must be an index below {size}, got "
                                   f"{brief(value)}")
    return value


def _number(value: Any, name: str) -> float | None:
    if value is not None and (not isinstance(value, float | int) or isinstance(value, bool)
                              or not math.isfinite(value)):
        raise InvalidArgumentError(f"snapshot.entities: {name!r} has a surface value "
                                   f"{brief(value)}")
    return None if value is None else float(value)


def _floats(value: Any, count: int | None = None) -> np.ndarray:
    if not isinstance(value, list) or (count is not None and len(value) != count) or \
            not all(isinstance(v, float | int) and not isinstance(v, bool) for v in value):
        raise InvalidArgumentError(f"snapshot: expected {count or 'some'} numbers, got "
                                   f"{brief(value)}")
    return np.array(value, dtype=float)


def _tuple(value: Any, count: int | None = None) -> tuple[float, ...]:
    return tuple(float(v) for v in _floats(value, count))


def _read_key(value: Any) -> tuple[Any, ...]:
    """A pool kind back from plain data: equal to what mujoco_pool.key_of makes."""
    if not isinstance(value, list) or len(value) != 4 or not isinstance(value[0], str) or \
            not isinstance(value[2], bool):
        raise InvalidArgumentError(f"snapshot: a pool kind is malformed: {brief(value)}")
    m = _fields(value[3], {"friction", "spin", "condim", "solref", "solimp", "rgba", "mass"},
                "pool kind material")
    if type(m["condim"]) is not int:
        raise InvalidArgumentError(f"snapshot: a pool kind's condim is {brief(m['condim'])}")
    rgba = None if m["rgba"] is None else _tuple(m["rgba"], 4)
    material = ms.Material(friction=float(_floats([m["friction"]])[0]),
                           spin=(lambda s: (s[0], s[1]))(_tuple(m["spin"], 2)),
                           condim=m["condim"],
                           solref=(lambda s: (s[0], s[1]))(_tuple(m["solref"], 2)),
                           solimp=_tuple(m["solimp"], 5),
                           rgba=None if rgba is None else (rgba[0], rgba[1], rgba[2], rgba[3]),
                           mass=None if m["mass"] is None else float(_floats([m["mass"]])[0]))
    return (value[0], _tuple(value[1]), value[2], material)


def _pool(engine: MujocoEngine, value: Any, kinds: list[tuple[Any, ...]]) -> None:
    row = _fields(value, {"serial", "parked"}, "pool")
    if type(row["serial"]) is not int or row["serial"] < 0:
        raise InvalidArgumentError(f"snapshot.pool.serial is {brief(row['serial'])}")
    parked: dict[tuple[Any, ...], list[Any]] = {}
    for pair in _list(row["parked"], "pool.parked"):
        if not isinstance(pair, list) or len(pair) != 2:
            raise InvalidArgumentError(f"snapshot.pool.parked holds {brief(pair)}")
        bodies = [engine._spec.body(n) if isinstance(n, str) else None
                  for n in _list(pair[1], "pool.parked[]")]
        if any(b is None for b in bodies):
            raise InvalidArgumentError("snapshot.pool.parked names a body the spec lacks")
        parked[kinds[_index(pair[0], len(kinds), "pool.parked[].kind")]] = bodies
    engine._pool._serial, engine._pool._parked = row["serial"], parked


def _joints(engine: MujocoEngine, infos: Any, targets: Any) -> None:
    if not isinstance(infos, dict) or not isinstance(targets, dict):
        raise InvalidArgumentError("snapshot.joints and snapshot.targets must be maps")
    joints = engine._joints
    try:
        joints.infos = {root: [JointInfo.from_wire(i) for i in _list(rows, "joints[]")]
                        for root, rows in infos.items()}
    except (TypeError, ValueError, KeyError, IndexError) as exc:
        raise InvalidArgumentError(f"snapshot.joints is malformed: {exc}") from exc
    if set(joints.infos) - set(engine._entities):
        raise InvalidArgumentError("snapshot.joints names a model the world lacks")
    joints.targets = {}
    for name, row in targets.items():
        if not isinstance(row, list) or len(row) != 5 or row[0] not in TARGET_MODES or \
                row[0] == "none":
            raise InvalidArgumentError(f"snapshot.targets[{name!r}] is malformed")
        joints.targets[name] = Target(row[0], *(float(v) for v in _floats(row[1:], 4)))


def _wrenches(engine: MujocoEngine, value: Any) -> None:
    if not isinstance(value, dict):
        raise InvalidArgumentError(f"snapshot.wrenches must be a map, got {brief(value)}")
    held = {}
    for name, packed in value.items():
        if name not in engine._entities:
            raise InvalidArgumentError(f"snapshot.wrenches names {brief(name)}, no entity")
        held[name] = arrays.unpack(packed, f"snapshot.wrenches[{name!r}]", arrays.F64,
                                   (6,)).copy()
    engine._wrenches.held = held
