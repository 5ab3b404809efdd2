"""The ODE engine's snapshots and restores (the data and its checks: snapshot/format.py).

``snapshot`` and ``restore`` are functions of the engine (``OdeEngine`` delegates to them):
they read and rebuild its bodies, models and wrenches.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.ode import spawn as spawning
from galton.daemon.engines.ode.native import LIB
from galton.daemon.engines.ode.snapshot import format as snapshots
from galton.daemon.engines.ode.spawn import ASLEEP, Body
from galton.protocol import BodyGroup, InvalidArgumentError

if TYPE_CHECKING:
    from galton.daemon.engines.ode.engine import OdeEngine


def snapshot(engine: OdeEngine, *, canonical: bool = True) -> dict[str, Any]:
    if canonical:
        engine.reset_dynamics()
    bodies = [_body_data(engine, b) for b in engine._bodies.values()
              if b.model is None or b.model == b.name]
    return {"format": snapshots.FORMAT, "version": snapshots.VERSION, "engine": engine.name,
            "params": engine.get_params(), "bodies": bodies, "diverged": engine._diverged}


def _body_data(engine: OdeEngine, body: Body) -> dict[str, Any]:
    if body.model is None:
        return snapshots.body_data(body, body.static or body.awake,
                                   engine._wrenches.get(body.name))
    model = engine._robots.models[body.name]
    links = [snapshots.body_data(b, b.awake, engine._wrenches.get(b.name))
             for b in engine._robots.links_of(body.name, engine._bodies)]
    joints = [{"name": j.info.name, "mode": j.info.mode, "target": j.target, "kp": j.kp,
               "kd": j.kd, "max_effort": j.max_effort, "effort": j.effort,
               **({"damping": j.info.damping} if j.scalar else {})}
              for j in model.joints]
    return snapshots.model_data(model.source, links, joints)


def restore(engine: OdeEngine, data: dict[str, Any]) -> None:
    params, bodies = snapshots.check(data)
    engine.set_params(params)
    for body in bodies:
        if "model" in body:
            _restore_model(engine, body)
        else:
            _restore_body(engine, body)
    engine._diverged = bool(data.get("diverged", False))


def _restore_model(engine: OdeEngine, data: dict[str, Any]) -> None:
    source = data["model"]
    engine.load_model("urdf", source["text"], source["path"], source["prefix"],
                    fixed_base=source["fixed_base"])
    for link in data["links"]:
        body = engine._lookup([link["name"]])[0]
        body.friction, body.restitution = link["friction"], link["restitution"]
        body.follows_friction, body.follows_restitution = link["follows"]
        _write_raw(engine, body, link)
    for joint in data["joints"]:
        held = engine._robots.by_name.get(joint["name"])
        if held is None:
            raise InvalidArgumentError(f"not an ode snapshot: no joint {joint['name']!r}")
        held.info.mode = joint["mode"]
        held.target, held.kp, held.kd = joint["target"], joint["kp"], joint["kd"]
        held.max_effort, held.effort = joint["max_effort"], joint["effort"]
        if "damping" in joint:
            engine._robots.put_back_damping(held.info.name, joint["damping"])
        if held.scalar:
            velocity = held.target if held.info.mode == "velocity" else 0.0
            damping = held.kd if held.info.mode in ("position", "velocity") else 0.0
            limit = np.inf if held.info.mode == "position" else held.max_effort
            held.motor(velocity, damping, limit)


def _restore_body(engine: OdeEngine, data: dict[str, Any]) -> None:
    static, state = data["static"], data["state"]
    pose = data["pose"] if static else state[0:3] + state[17:20] + state[16:17]
    mesh = snapshots.mesh_of(data, data["name"])
    group = BodyGroup(data["shape"], tuple(data["size"]), [data["name"]],
                      np.array([pose], dtype=float), static=static, mass=data["mass"],
                      friction=data["friction"], restitution=data["restitution"],
                      rgba=None if data["rgba"] is None else tuple(data["rgba"]),
                      inertia=_inertia(data),
                      vertices=None if mesh is None else mesh[0],
                      faces=None if mesh is None else mesh[1])
    made = spawning.spawn_group(engine._world, engine._space, group, engine._values)
    body = made[0]
    body.follows_friction, body.follows_restitution = data["follows"]
    engine._adopt(made)
    if not static:
        _write_raw(engine, body, data)


def _write_raw(engine: OdeEngine, body: Body, data: dict[str, Any]) -> None:
    state = data["state"]
    LIB.dBodySetPosition(body.body, *state[:3])  # marks the geoms moved
    body.state[:] = state  # ODE's own doubles, as they were
    if not data["enabled"]:
        LIB.dBodyDisable(body.body)
        body.awake = False
        body.set_bits(ASLEEP)
    if data["wrench"] is not None:
        engine._wrenches[body.name] = [float(v) for v in data["wrench"]]
        LIB.dBodySetAutoDisableFlag(body.body, 0)


def _inertia(data: dict[str, Any]) -> tuple[float, float, float] | None:
    """A snapshot body's own inertia (kg m²) from its moments per kg and its mass."""
    unit = data.get("unit_inertia")
    if unit is None:
        return None
    ixx, iyy, izz = (float(data["mass"]) * float(i) for i in unit)
    return (ixx, iyy, izz)
