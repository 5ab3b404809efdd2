"""Snapshots of the MuJoCo world as plain data, and restoring one on a fresh engine.

A snapshot holds the world's spec as MJCF (its structure: bodies in their order, frames,
geoms, joints, actuators, loaded models' assets -- meshes by file name), the compiled
model's and the data's numbers exactly (``snapshot_arrays``: XML keeps six digits),
the parameters, and the engine's own records: entities, the pool of parked bodies, loaded
models' joints and held targets, held wrenches, the sleep guard, and the counters of the
periodic looks. Restoring parses the MJCF, compiles it, writes the exact numbers into the
model, writes them back into the spec (``MjSpec.copy_back``: later recompiles start from
the same values as the source's) and into a fresh MjData, then rebuilds the records.

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

from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import params as mparams
from galton.daemon.engines.mujoco.entities import MUJOCO_ERRORS, Entity
from galton.daemon.engines.mujoco.snapshot import arrays
from galton.daemon.engines.mujoco.snapshot.format import read_records
from galton.daemon.engines.params import check_updates
from galton.protocol import InvalidArgumentError, OperationFailedError
from galton.protocol.errors import brief

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

# 2: the bodies' order travels (format 1 could restore them permuted); 3: the meshes'
# vertices travel exactly (MJCF's six digits moved a prism's, and its geom's size with them).
FORMAT = 3
ENGINE = "mujoco"
SIZES = ("nbody", "ngeom", "njnt", "nq", "nv", "nu", "ntree", "nmocap")
KEYS = frozenset({"format", "engine", "engine_version", "params", "spec", "memory", "sizes",
                  "bodies",
                  "model", "data", "entities", "loads", "kinds", "pool", "joints", "targets",
                  "wrenches", "balance", "looks", "meshes"})


# -- taking a snapshot ----------------------------------------------------------------------
def snapshot(engine: MujocoEngine) -> dict[str, Any]:
    if engine.broken:
        raise OperationFailedError("the MuJoCo world is broken (a failed step or delete); "
                                   "reset it before taking a snapshot")
    if engine.parked_edited:
        _recompile(engine)
    m, d = engine.model, engine.data
    loads: dict[int, int] = {}  # id(Assets) -> its place in "loads"
    kinds: dict[tuple[Any, ...], int] = {}  # pool kind -> its place in "kinds"
    entities = [_entity(name, e, loads, kinds) for name, e in engine.entities.items()]
    parked = [[kinds.setdefault(key, len(kinds)), [b.name for b in bodies]]
              for key, bodies in engine.parked._parked.items()]
    assets = {id(e.assets): e.assets for e in engine.entities.values() if e.assets}
    return {
        "format": FORMAT, "engine": ENGINE, "engine_version": mujoco.__version__,
        "params": engine.get_params(), "spec": _xml(engine),
        "meshes": _mesh_vertices(engine.mj_spec),
        "memory": int(engine.mj_spec.memory), "sizes": {s: int(getattr(m, s)) for s in SIZES},
        "bodies": _body_order(engine.mj_spec),
        "model": arrays.model_numbers(m), "data": arrays.data_numbers(m, d),
        "entities": entities,
        "loads": [{"assets": sorted([k, n] for k, n in assets[i].names),
                   "roots": assets[i].roots} for i in sorted(loads, key=loads.__getitem__)],
        "kinds": [_key(key) for key in kinds],
        "pool": {"serial": engine.parked._serial, "parked": parked},
        "joints": {root: [i.to_wire() for i in infos]
                   for root, infos in engine.loaded_joints.infos.items()},
        "targets": {n: [t.mode, t.target, t.kp, t.kd, t.max_effort]
                    for n, t in engine.loaded_joints.targets.items()},
        "wrenches": {n: arrays.pack(w) for n, w in engine.wrenches.held.items()},
        "balance": None if engine.sleep_guard is None else engine.sleep_guard.records(),
        "looks": {"diverged": engine.diverged, "crowded": engine.crowded,
                  "steps_since_look": engine.steps_since_look},
    }


def _xml(engine: MujocoEngine) -> str:
    """The spec as MJCF: 50 ms for a 500-ball board, so kept until the spec changes (a
    compile, a parameter, an update, a static body moved; pool edits recompile first)."""
    if engine.xml is None:
        engine.xml = engine.mj_spec.to_xml()
    return engine.xml


def _mesh_vertices(spec: mujoco.MjSpec) -> dict[str, Any]:
    """Each mesh's vertices as the spec holds them: its MJCF has six digits only (empty for
    a mesh a model loads from a file, which compiles alike from that file)."""
    return {mesh.name: arrays.pack(np.asarray(mesh.uservert, dtype=np.float32), arrays.F32)
            for mesh in spec.meshes}


def _write_mesh_vertices(spec: mujoco.MjSpec, meshes: Any) -> None:
    """Put back the exact vertices of every mesh the MJCF names (and only those)."""
    table = arrays.names_map(meshes, "snapshot.meshes")
    named = {mesh.name: mesh for mesh in spec.meshes}
    if set(table) != set(named):
        raise InvalidArgumentError(
            f"snapshot.spec compiles to a world of the meshes {sorted(named)[:5]}, not of the "
            f"snapshot's meshes {sorted(table)[:5]}")
    exact = {name: arrays.unpack(table[name], f"snapshot.meshes.{name}", arrays.F32,
                                 (len(mesh.uservert),)) for name, mesh in named.items()}
    for name, vertices in exact.items():
        if not np.isfinite(vertices).all():
            raise InvalidArgumentError(f"snapshot.meshes.{name} holds a vertex that is not "
                                       "finite")
    for name, vertices in exact.items():
        named[name].uservert = vertices.astype(np.float64)


def _body_order(spec: mujoco.MjSpec) -> list[str]:
    """The bodies' names in the compiled model's order (the spec's tree order; the model's
    own names may still be the temporary ones of an attach)."""
    return [body.name for body in spec.bodies]


def _recompile(engine: MujocoEngine) -> None:
    """Compile the model as its spec compiles it, as a restore will: binding and parking
    bodies in the pool edit the compiled model alone (collisions, hence its bounding volume
    hierarchy). The bodies stay where they are in the model, so the whole data, sleep records
    included, and the sleep guard's records are carried over exactly."""
    numbers = arrays.data_numbers(engine.model, engine.data)
    guard = None if engine.sleep_guard is None else engine.sleep_guard.records()
    engine.recompile()
    arrays.write_data_numbers(engine.model, engine.data, numbers)
    if guard is not None and engine.sleep_guard is not None:
        engine.sleep_guard.load(engine.model, guard)


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
    """A pool kind (parked.key_of) as plain data."""
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
    _write_mesh_vertices(spec, data["meshes"])
    try:
        model = spec.compile()
    except MUJOCO_ERRORS as exc:
        raise InvalidArgumentError(f"snapshot.spec does not compile: {exc}") from exc
    _check_sizes(model, data["sizes"])
    _check_order(model, data["bodies"])
    arrays.write_model_numbers(model, data["model"])
    try:
        spec.copy_back(model)
    except MUJOCO_ERRORS as exc:
        raise InvalidArgumentError(f"snapshot.model does not fit its spec: {exc}") from exc
    # copy_back carries the model's statistics into the spec, and a spec that sets
    # meaninertia (deprecated by MuJoCo: it does not affect simulation) makes every later
    # compile log a deprecation warning: each compile works it out again instead.
    spec.stat.meaninertia = math.nan
    state = mujoco.MjData(model)
    arrays.write_data_numbers(model, state, data["data"])
    engine.values, engine.mj_spec = values, spec
    engine.model, engine.data, engine.empty_frames = model, state, []
    engine.xml = data["spec"]  # compiles to this world as well as its own MJCF would
    read_records(engine, data)
    engine.workers = 0
    engine.start_workers()


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
    if not isinstance(params, dict) or set(params) != set(mparams.PARAMS):
        raise InvalidArgumentError(f"snapshot.params must give every MuJoCo parameter, got "
                                   f"{brief(params)}")
    return {**{n: p.default for n, p in mparams.PARAMS.items()},
            **check_updates(ENGINE, mparams.PARAMS, params)}


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


def _check_order(model: mujoco.MjModel, bodies: Any) -> None:
    """The arrays are by position: the MJCF must compile the bodies in the order they were
    taken in, or each body would get another's numbers."""
    made = [model.body(i).name for i in range(model.nbody)]
    if bodies != made:
        first = next((i for i, (a, b) in enumerate(zip(made, bodies, strict=False)) if a != b),
                     min(len(made), len(bodies) if isinstance(bodies, list) else 0))
        raise InvalidArgumentError(
            f"snapshot.spec compiles its bodies in another order than snapshot.bodies (the "
            f"order its arrays were taken in), first at body {first}: "
            f"{brief(made[first] if first < len(made) else None)}")
