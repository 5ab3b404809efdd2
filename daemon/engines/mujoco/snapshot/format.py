"""The MuJoCo engine's own records read back from a snapshot (``snapshot``), each value
checked as the untrusted input it is: entities with their spec bodies, models' assets, the
pool's parked bodies by kind, loaded models' joints and held targets, held wrenches, the
sleep guard and the counters of the periodic looks.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines.base import Target
from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco.entities import ASSET_KINDS, Assets, Entity
from galton.daemon.engines.mujoco.model_setup import body_name
from galton.daemon.engines.mujoco.snapshot import arrays
from galton.protocol import TARGET_MODES, GaltonError, InvalidArgumentError, JointInfo
from galton.protocol.errors import brief

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

SOURCES = ("spawn", "model", "link")


def read_records(engine: MujocoEngine, data: dict[str, Any]) -> None:
    """The snapshot's records into the engine whose spec, model and data it now holds."""
    loads = [_load(i, load) for i, load in enumerate(_list(data["loads"], "loads"))]
    kinds = [_read_key(kind) for kind in _list(data["kinds"], "kinds")]
    engine.entities = {}
    for row in _list(data["entities"], "entities"):
        name, entity = _read_entity(engine.mj_spec, row, loads, kinds)
        engine.entities[name] = entity
    engine.parts = {n for n, e in engine.entities.items() if e.source == "link"}
    engine.models = sum(e.source == "model" for e in engine.entities.values())
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
    engine.diverged, engine.crowded = looks["diverged"], looks["crowded"]
    engine.steps_since_look = steps
    try:
        engine.reindex()  # writes the held targets and wrenches into the model and data
    except InvalidArgumentError:
        raise
    except (GaltonError, KeyError, IndexError) as exc:
        raise InvalidArgumentError(f"snapshot names what its world lacks: {exc}") from exc
    balance = data["balance"]
    if (balance is None) != (engine.sleep_guard is None):
        raise InvalidArgumentError("snapshot.balance must be given exactly when "
                                   "mujoco.wake_balanced is on")
    if engine.sleep_guard is not None:
        engine.sleep_guard.load(engine.model, balance)


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


def _floats(value: Any, count: int | None = None, *, allow_inf: bool = False) -> np.ndarray:
    """Numbers, never NaN (it would reach MuJoCo's model or state); infinity only where
    it means "no bound" (a target's max_effort)."""
    if not isinstance(value, list) or (count is not None and len(value) != count) or \
            not all(isinstance(v, float | int) and not isinstance(v, bool) for v in value):
        raise InvalidArgumentError(f"snapshot: expected {count or 'some'} numbers, got "
                                   f"{brief(value)}")
    array = np.array(value, dtype=float)
    if not (np.isfinite(array) | (allow_inf & np.isinf(array))).all():
        raise InvalidArgumentError(f"snapshot: expected {count or 'some'} finite numbers, got "
                                   f"{brief(value)}")
    return array


def _tuple(value: Any, count: int | None = None) -> tuple[float, ...]:
    return tuple(float(v) for v in _floats(value, count))


def _read_key(value: Any) -> tuple[Any, ...]:
    """A pool kind back from plain data: equal to what parked.key_of makes."""
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
        raise InvalidArgumentError(f"snapshot.parked.serial is {brief(row['serial'])}")
    parked: dict[tuple[Any, ...], list[Any]] = {}
    for pair in _list(row["parked"], "pool.parked"):
        if not isinstance(pair, list) or len(pair) != 2:
            raise InvalidArgumentError(f"snapshot.parked.parked holds {brief(pair)}")
        bodies = [engine.mj_spec.body(n) if isinstance(n, str) else None
                  for n in _list(pair[1], "pool.parked[]")]
        if any(b is None for b in bodies):
            raise InvalidArgumentError("snapshot.parked.parked names a body the spec lacks")
        parked[kinds[_index(pair[0], len(kinds), "pool.parked[].kind")]] = bodies
    engine.parked._serial, engine.parked._parked = row["serial"], parked


def _joints(engine: MujocoEngine, infos: Any, targets: Any) -> None:
    if not isinstance(infos, dict) or not isinstance(targets, dict):
        raise InvalidArgumentError("snapshot.joints and snapshot.targets must be maps")
    joints = engine.loaded_joints
    try:
        joints.infos = {root: [JointInfo.from_wire(i) for i in _list(rows, "joints[]")]
                        for root, rows in infos.items()}
    except (TypeError, ValueError, KeyError, IndexError) as exc:
        raise InvalidArgumentError(f"snapshot.joints is malformed: {exc}") from exc
    if set(joints.infos) - set(engine.entities):
        raise InvalidArgumentError("snapshot.joints names a model the world lacks")
    joints.own = {i.name: i.damping for rows in joints.infos.values() for i in rows if i.scalar}
    joints.targets = {}
    for name, row in targets.items():
        if not isinstance(row, list) or len(row) != 5 or row[0] not in TARGET_MODES or \
                row[0] == "none":
            raise InvalidArgumentError(f"snapshot.targets[{name!r}] is malformed")
        numbers = _floats(row[1:], 4, allow_inf=True)  # max_effort inf: unbounded
        joints.targets[name] = Target(row[0], *(float(v) for v in numbers))


def _wrenches(engine: MujocoEngine, value: Any) -> None:
    if not isinstance(value, dict):
        raise InvalidArgumentError(f"snapshot.wrenches must be a map, got {brief(value)}")
    held = {}
    for name, packed in value.items():
        if name not in engine.entities:
            raise InvalidArgumentError(f"snapshot.wrenches names {brief(name)}, no entity")
        held[name] = arrays.unpack(packed, f"snapshot.wrenches[{name!r}]", arrays.F64,
                                   (6,)).copy()
    engine.wrenches.held = held
