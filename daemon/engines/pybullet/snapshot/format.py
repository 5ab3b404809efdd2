"""A PyBullet snapshot's format: a world as plain data and back. A snapshot holds the
world's rebuild plan (rebuild.Plan), its parameters and its next batch number.

Layout (format 1), every array packed as arrays.pack makes it::

    format, engine ("pybullet"), engine_version, params {name: value}, next_batch,
    runs [spawn or model run, in the order made], poses (n, 7), twists (n, 6),
    exact [bool] (poses given since the last step), models [articulation], wrenches

A spawn run is what is left of one spawn group (its values shared, its bodies' own ones
as columns); a model run what is left of one model load (its text, each body's place in
the load, link masses, state as loaded and edits). An articulation holds a model's links,
joints and the targets its 1-DOF joints hold. Bodies' PyBullet ids are not kept: a world
made from the plan hands them out again, in the same order.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from galton.daemon.engines.geometry import unit_inertia
from galton.daemon.engines.params import check_updates
from galton.daemon.engines.pybullet.joints import Articulation
from galton.daemon.engines.pybullet.models import MODEL_FORMATS
from galton.daemon.engines.pybullet.params import PARAMS
from galton.daemon.engines.pybullet.rebuild import Body, Model, Plan, batches, own_inertia
from galton.daemon.engines.pybullet.robots import JointStates, Robots
from galton.daemon.engines.pybullet.snapshot import arrays as sd
from galton.protocol import BodyProperties, InvalidArgumentError, JointInfo
from galton.protocol import mesh as mesh_wire
from galton.protocol.errors import brief
from galton.protocol.model import check_type
from galton.protocol.vocabulary import (
    BODY_SHAPES,
    JOINT_TYPES,
    POSE_WIDTH,
    SIZE_LAYOUT,
    TARGET_MODES,
    TWIST_WIDTH,
)

FORMAT = 1
ENGINE = "pybullet"
TOP = ("format", "engine", "engine_version", "params", "next_batch", "runs", "poses",
       "twists", "exact", "models", "wrenches")
SPAWN_RUN = ("kind", "batch", "names", "shape", "size", "static", "made_mass", "turn",
             "turned", "mass", "friction", "restitution", "rgba", "follows_friction",
             "follows_restitution", "vertices", "faces", "inertia")
MODEL_RUN = ("kind", "batch", "names", "fmt", "text", "path", "fixed_base", "index", "links",
             "loaded", "edits")
ARTICULATION = ("root", "links", "joints", "indices", "loaded", "law", "active", "state")
JOINT = ("name", "model", "type", "parent", "child", "axis", "lower", "upper", "damping",
         "effort_limit", "velocity_limit", "mode")
LAW = ("gain", "bias_q", "bias_v", "target", "max_effort", "effort")  # Articulation's arrays
MAX_BATCH = 2**31 - 1
MAX_INDEX = 100_000  # a body's place in its model load, a joint's index in its body
MAX_SIZE, MAX_MASS = 1e4, 1e9  # as the protocol's spawn checks


@dataclass(slots=True)
class Restored:
    """A snapshot read back: what the engine rebuilds its world from."""

    plan: Plan
    params: dict[str, Any]
    next_batch: int


# -- to plain data ---------------------------------------------------------------------------
def encode(plan: Plan, params: dict[str, Any], next_batch: int, version: str) -> dict[str, Any]:
    bodies, names = plan.bodies, list(plan.bodies)
    runs = [model_run(run, bodies) if bodies[run[0]].model is not None
            else spawn_run(run, bodies) for run in batches(bodies)]
    return {
        "format": FORMAT, "engine": ENGINE, "engine_version": version,
        "params": {k: list(v) if isinstance(v, tuple) else v for k, v in params.items()},
        "next_batch": next_batch, "runs": runs,
        "poses": sd.pack(np.array([plan.states[n][0] for n in names]).reshape(-1, POSE_WIDTH)),
        "twists": sd.pack(np.array([plan.states[n][1] for n in names]).reshape(
            -1, TWIST_WIDTH)),
        "exact": [n in plan.exact for n in names],
        "models": [articulation(model, plan.joints.get(root))
                   for root, model in plan.robots.models.items()],
        "wrenches": {"names": list(plan.robots.wrenches), "values": sd.pack(np.array(
            [[*f, *t] for f, t in plan.robots.wrenches.values()]).reshape(-1, 6))},
    }


def spawn_run(names: list[str], bodies: dict[str, Body]) -> dict[str, Any]:
    """One spawn group's remaining bodies: shared values once, their own as columns."""
    run = [bodies[name] for name in names]
    first = run[0]
    nan = (math.nan,) * 4
    return {
        "kind": "spawn", "batch": first.batch, "names": names, "shape": first.shape,
        "size": list(first.size), "static": first.static, "made_mass": first.made_mass,
        "turn": list(first.turn), "turned": [b.turned for b in run],
        "mass": sd.pack([b.mass for b in run]), "friction": sd.pack([b.friction for b in run]),
        "restitution": sd.pack([b.restitution for b in run]),
        "rgba": sd.pack([b.rgba or nan for b in run]),
        "follows_friction": [b.follows_friction for b in run],
        "follows_restitution": [b.follows_restitution for b in run],
        "vertices": None if first.mesh is None else mesh_wire.pack_vertices(first.mesh[0]),
        "faces": None if first.mesh is None else mesh_wire.pack_faces(first.mesh[1]),
        "inertia": None if (own := own_inertia(first)) is None else list(own),
    }


def model_run(names: list[str], bodies: dict[str, Body]) -> dict[str, Any]:
    """One model load's remaining bodies: its text once, each body's records."""
    models = [body.model for name in names if (body := bodies[name]).model is not None]
    first = models[0]
    return {
        "kind": "model", "batch": bodies[names[0]].batch, "names": names, "fmt": first.fmt,
        "text": first.text, "path": first.path, "fixed_base": first.fixed_base,
        "index": [m.index for m in models],
        "links": [sd.pack([[mass, *inertia] for mass, inertia in m.links]) for m in models],
        "loaded": sd.pack([[*m.loaded[0], *m.loaded[1]] for m in models]),
        "edits": [m.edits.to_wire() for m in models],
    }


def articulation(model: Articulation, state: tuple[np.ndarray, np.ndarray] | None
                 ) -> dict[str, Any]:
    n = len(model.indices)
    q, qdot = state if state is not None else (np.zeros(n), np.zeros(n))
    return {
        "root": model.root, "links": list(model.links),
        "joints": [info.to_wire() for info in model.infos], "indices": list(model.indices),
        "loaded": sd.pack(np.reshape(model.loaded, (2, n))),
        "law": sd.pack(np.reshape([getattr(model, key) for key in LAW], (len(LAW), n))),
        "active": model.active, "state": sd.pack(np.reshape([q, qdot], (2, n))),
    }


# -- from plain data -------------------------------------------------------------------------
def decode(data: Any) -> Restored:
    """A snapshot checked whole, as untrusted input, before the world changes."""
    check_type(data, dict, "snapshot")
    if data.get("engine") != ENGINE:
        raise InvalidArgumentError(f"this is a snapshot of the {brief(data.get('engine'))} "
                                   f"engine; a {ENGINE} world restores only its own")
    if data.get("format") != FORMAT or isinstance(data.get("format"), bool):
        raise InvalidArgumentError(f"snapshot format {brief(data.get('format'))} is not "
                                   f"{FORMAT}, the one this {ENGINE} engine reads")
    sd.fields(data, TOP, "snapshot")
    sd.text(data["engine_version"], "snapshot.engine_version")
    params = read_params(data["params"])
    next_batch = sd.count(data["next_batch"], "snapshot.next_batch", high=MAX_BATCH)
    bodies = read_runs(data["runs"], next_batch)
    n = len(bodies)
    poses = sd.unpack(data["poses"], (n, POSE_WIDTH), "snapshot.poses")
    norms = np.linalg.norm(poses[:, 3:], axis=1)
    if n and np.abs(norms - 1).max() > 1e-6:
        raise InvalidArgumentError("snapshot.poses holds a quaternion that is not of unit norm")
    twists = sd.unpack(data["twists"], (n, TWIST_WIDTH), "snapshot.twists")
    exact = sd.flags(data["exact"], n, "snapshot.exact")
    states = {name: (pose, twist) for name, pose, twist in zip(
        bodies, poses.tolist(), twists.tolist(), strict=True)}
    robots, joints = read_robots(data["models"], bodies)
    read_wrenches(data["wrenches"], robots, bodies)
    plan = Plan(bodies, states, {name for name, e in zip(bodies, exact, strict=True) if e},
                robots, {}, joints)
    return Restored(plan, params, next_batch)


def read_params(value: Any) -> dict[str, Any]:
    record = sd.fields(value, tuple(PARAMS), "snapshot.params")
    return check_updates(ENGINE, PARAMS, record)


def read_runs(value: Any, next_batch: int) -> dict[str, Body]:
    """Every body's records, run by run, in the order made (batches strictly increasing)."""
    check_type(value, list, "snapshot.runs")
    bodies: dict[str, Body] = {}
    last = -1
    for k, run in enumerate(value):
        where = f"snapshot.runs[{k}]"
        kind = check_type(run, dict, where).get("kind")
        if kind not in ("spawn", "model"):
            raise InvalidArgumentError(f"{where}.kind must be 'spawn' or 'model', "
                                       f"got {brief(kind)}")
        made = read_spawn(run, where) if kind == "spawn" else read_model(run, where)
        batch = next(iter(made.values())).batch
        if not last < batch < next_batch:
            raise InvalidArgumentError(f"{where}.batch {batch} is not after the run before "
                                       f"({last}) and before next_batch ({next_batch})")
        last = batch
        sd.unique(set(bodies), list(made), where)
        bodies.update(made)
    return bodies


def read_spawn(value: dict[str, Any], where: str) -> dict[str, Body]:
    run = sd.fields(value, SPAWN_RUN, where)
    batch = sd.count(run["batch"], f"{where}.batch", high=MAX_BATCH)
    names = sd.names(run["names"], f"{where}.names")
    n = len(names)
    if not n:
        raise InvalidArgumentError(f"{where}.names is empty")
    shape = run["shape"]
    if shape not in BODY_SHAPES:
        raise InvalidArgumentError(f"{where}.shape {brief(shape)} is not one of "
                                   f"{', '.join(BODY_SHAPES)}")
    size = sd.numbers(run["size"], len(SIZE_LAYOUT[shape]), f"{where}.size", high=MAX_SIZE)
    static = sd.flag(run["static"], f"{where}.static")
    if min(size) <= 0 or (shape == "plane" and not static):
        raise InvalidArgumentError(f"{where}: a size must be positive and a plane static")
    low = 0.0 if static else 1e-300
    made_mass = sd.number(run["made_mass"], f"{where}.made_mass", low=low,
                          high=0.0 if static else MAX_MASS)
    turn = sd.numbers(run["turn"], 4, f"{where}.turn", low=-1.0, high=1.0)
    if abs(math.hypot(*turn) - 1) > 1e-6:
        raise InvalidArgumentError(f"{where}.turn is not a unit quaternion")
    mass = sd.unpack(run["mass"], (n,), f"{where}.mass")
    if (mass < low).any() or (mass > (0.0 if static else MAX_MASS)).any():
        raise InvalidArgumentError(f"{where}.mass is out of range (0 when static)")
    surface = in_range(sd.unpack(run["friction"], (n,), f"{where}.friction"), 100.0,
                       f"{where}.friction"), in_range(sd.unpack(
                           run["restitution"], (n,), f"{where}.restitution"), 1.0,
                           f"{where}.restitution")
    rgba = read_rgba(run["rgba"], n, f"{where}.rgba")
    turned = sd.flags(run["turned"], n, f"{where}.turned")
    follows = (sd.flags(run["follows_friction"], n, f"{where}.follows_friction"),
               sd.flags(run["follows_restitution"], n, f"{where}.follows_restitution"))
    mesh = read_mesh(run, shape, where)
    own = read_inertia(run["inertia"], static, f"{where}.inertia")
    inertia = None if static else unit_inertia("box" if shape == "mesh" else shape, size)
    if own is not None:
        inertia = (own[0] / made_mass, own[1] / made_mass, own[2] / made_mass)
    return {name: Body(-1, static, shape, size, inertia, batch, mesh=mesh,
                       own_inertia=own is not None, follows_friction=follows[0][k],
                       follows_restitution=follows[1][k], mass=float(mass[k]),
                       made_mass=made_mass, turn=turn, turned=turned[k],
                       friction=float(surface[0][k]), restitution=float(surface[1][k]),
                       rgba=rgba[k]) for k, name in enumerate(names)}


def read_mesh(run: dict[str, Any], shape: str, where: str
              ) -> tuple[np.ndarray, np.ndarray] | None:
    """A mesh run's vertices and faces, checked as spawn checks them; none for the rest."""
    if shape != "mesh":
        if run["vertices"] is not None or run["faces"] is not None:
            raise InvalidArgumentError(f"{where}: only a mesh has vertices and faces")
        return None
    vertices = mesh_wire.decode_vertices(run["vertices"], f"{where}.vertices")
    faces = mesh_wire.decode_faces(run["faces"], len(vertices), f"{where}.faces")
    return vertices, faces


def read_inertia(value: Any, static: bool, where: str) -> tuple[float, float, float] | None:
    if value is None:
        return None
    if static:
        raise InvalidArgumentError(f"{where}: a static body has no inertia")
    ixx, iyy, izz = sd.numbers(value, 3, where, low=1e-300, high=MAX_MASS)
    return (ixx, iyy, izz)


def in_range(values: np.ndarray, high: float, where: str) -> np.ndarray:
    if (values < 0).any() or (values > high).any():
        raise InvalidArgumentError(f"{where} holds a value outside [0, {high}]")
    return values


def read_rgba(value: Any, n: int, where: str) -> list[tuple[float, float, float, float] | None]:
    """Colours, a row of NaN for the default look."""
    rows = sd.unpack(value, (n, 4), where, finite=False)
    unset = np.isnan(rows).all(axis=1)
    if np.isinf(rows).any() or (np.isnan(rows).any(axis=1) != unset).any() or (
            (rows[~unset] < 0).any() or (rows[~unset] > 1).any()):
        raise InvalidArgumentError(f"{where} holds a colour outside [0, 1] (NaN rows: none)")
    return [None if unset[k] else (row[0], row[1], row[2], row[3])
            for k, row in enumerate(rows.tolist())]


def read_model(value: dict[str, Any], where: str) -> dict[str, Body]:
    run = sd.fields(value, MODEL_RUN, where)
    batch = sd.count(run["batch"], f"{where}.batch", high=MAX_BATCH)
    names = sd.names(run["names"], f"{where}.names")
    n = len(names)
    fmt = run["fmt"]
    if not n or fmt not in MODEL_FORMATS:
        raise InvalidArgumentError(f"{where}: a model run names at least one body and has a "
                                   f"format in {', '.join(MODEL_FORMATS)}")
    text = sd.text(run["text"], f"{where}.text")
    path = None if run["path"] is None else sd.text(run["path"], f"{where}.path")
    fixed = sd.flag(run["fixed_base"], f"{where}.fixed_base")
    index = check_type(run["index"], list, f"{where}.index")
    index = [sd.count(i, f"{where}.index[{k}]", high=MAX_INDEX) for k, i in enumerate(index)]
    if len(index) != n or any(b <= a for a, b in itertools.pairwise(index)):
        raise InvalidArgumentError(f"{where}.index must hold {n} increasing places")
    links = check_type(run["links"], list, f"{where}.links")
    if len(links) != n:
        raise InvalidArgumentError(f"{where}.links must hold {n} link tables")
    loaded = sd.unpack(run["loaded"], (n, POSE_WIDTH + TWIST_WIDTH), f"{where}.loaded").tolist()
    edits = check_type(run["edits"], list, f"{where}.edits")
    if len(edits) != n:
        raise InvalidArgumentError(f"{where}.edits must hold {n} records")
    out = {}
    for k, name in enumerate(names):
        table = link_table(links[k], f"{where}.links[{k}]")
        edit = BodyProperties.from_wire(edits[k], f"{where}.edits[{k}]")
        model = Model(fmt, text, path, index[k], table,
                      (loaded[k][:POSE_WIDTH], loaded[k][POSE_WIDTH:]), edit, fixed)
        out[name] = Body(-1, False, "model", (), None, batch, model=model)
    return out


def link_table(value: Any, where: str) -> tuple[tuple[float, tuple[float, ...]], ...]:
    """A model body's link masses and inertia diagonals, base first."""
    rows = check_type(value, dict, where).get("shape")
    count = rows[0] if isinstance(rows, list) and rows else 0
    if not isinstance(count, int) or not 1 <= count <= MAX_INDEX:
        raise InvalidArgumentError(f"{where} must have shape [links, 4] with 1 to "
                                   f"{MAX_INDEX} links")
    table = sd.unpack(value, (count, 4), where)
    if (table < 0).any():
        raise InvalidArgumentError(f"{where} holds a negative mass or inertia")
    return tuple((row[0], (row[1], row[2], row[3])) for row in table.tolist())


def read_robots(value: Any, bodies: dict[str, Body]) -> tuple[Robots, JointStates]:
    """The models' articulations; their roots must be model bodies, their links new names."""
    check_type(value, list, "snapshot.models")
    robots, joints = Robots(), {}
    seen = set(bodies)
    for k, record in enumerate(value):
        where = f"snapshot.models[{k}]"
        model, state = read_articulation(record, where)
        body = bodies.get(model.root)
        if body is None or body.model is None or model.root in robots.models:
            raise InvalidArgumentError(f"{where}.root {model.root!r} is not a model body of "
                                       "the snapshot, or has two articulations")
        sd.unique(seen, model.links, f"{where}.links")
        robots.add(model)
        if model.indices:
            joints[model.root] = state
    names = [info.name for model in robots.models.values() for info in model.infos]
    if len(set(names)) != len(names):
        raise InvalidArgumentError("snapshot.models name a joint twice")
    return robots, joints


def read_articulation(value: Any, where: str
                      ) -> tuple[Articulation, tuple[np.ndarray, np.ndarray]]:
    record = sd.fields(value, ARTICULATION, where)
    root = sd.names([record["root"]], f"{where}.root")[0]
    links = sd.names(record["links"], f"{where}.links", hidden=True)
    infos = [read_joint(j, f"{where}.joints[{k}]")
             for k, j in enumerate(check_type(record["joints"], list, f"{where}.joints"))]
    indices = check_type(record["indices"], list, f"{where}.indices")
    indices = [sd.count(i, f"{where}.indices[{k}]", high=len(links) - 1)
               for k, i in enumerate(indices)]
    scalar = [info.name for info in infos if info.scalar]
    if len(scalar) != len(indices) or len(set(indices)) != len(indices):
        raise InvalidArgumentError(f"{where}.indices must be {len(scalar)} distinct joint "
                                   "indices, one per 1-DOF joint")
    n = len(indices)
    loaded = sd.unpack(record["loaded"], (2, n), f"{where}.loaded")
    model = Articulation(root, links, infos, {name: k for k, name in enumerate(scalar)},
                         indices, (loaded[0], loaded[1]))
    law = sd.unpack(record["law"], (len(LAW), n), f"{where}.law", allow_inf=True)
    if np.isinf(law[:4]).any() or np.isinf(law[5]).any() or (law[4] < 0).any():
        raise InvalidArgumentError(f"{where}.law: only max_effort may be infinite, and it "
                                   "is not negative")
    for key, row in zip(LAW, law, strict=True):
        setattr(model, key, row.copy())
    for info, joint in zip(infos, record["joints"], strict=True):
        info.mode = joint["mode"]  # Articulation() released every target
    model.active = sd.flag(record["active"], f"{where}.active")
    state = sd.unpack(record["state"], (2, n), f"{where}.state")
    return model, (state[0], state[1])


def read_joint(value: Any, where: str) -> JointInfo:
    record = sd.fields(value, JOINT, where)
    texts = [sd.text(record[key], f"{where}.{key}")
             for key in ("name", "model", "type", "parent", "child", "mode")]
    if texts[2] not in JOINT_TYPES or texts[5] not in TARGET_MODES:
        raise InvalidArgumentError(f"{where}: type {texts[2]!r} or mode {texts[5]!r} unknown")
    axis = sd.numbers(record["axis"], 3, f"{where}.axis")
    limits = [sd.optional(record[key], f"{where}.{key}")
              for key in ("lower", "upper", "effort_limit", "velocity_limit")]
    return JointInfo(texts[0], texts[1], texts[2], texts[3], texts[4], (axis[0], axis[1], axis[2]),
                     limits[0], limits[1], sd.number(record["damping"], f"{where}.damping"),
                     limits[2], limits[3], texts[5])


def read_wrenches(value: Any, robots: Robots, bodies: dict[str, Body]) -> None:
    record = sd.fields(value, ("names", "values"), "snapshot.wrenches")
    names = sd.names(record["names"], "snapshot.wrenches.names")
    rows = sd.unpack(record["values"], (len(names), 6), "snapshot.wrenches.values").tolist()
    unknown = [name for name in names if name not in bodies and name not in robots.links]
    if unknown:
        raise InvalidArgumentError(f"snapshot.wrenches: no entity named {unknown[0]!r}")
    robots.wrenches.update((name, (row[:3], row[3:])) for name, row in zip(
        names, rows, strict=True))
