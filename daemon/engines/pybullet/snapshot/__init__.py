"""The PyBullet engine's snapshots: its world as plain data (snapshot/format.py), and a
fresh engine made into that world.

Bullet's contact points and their warm-start impulses cannot be read out, so a snapshot
cannot carry them. Instead, taking one makes the source world's hidden state canonical:
the world is rebuilt from its records (as ``reset_dynamics`` does, rebuild.py), and
a restore makes the same world through the same calls in the same order. Both then start
from a world with no contact history, and go on alike bit for bit. That costs the source
a rebuild (about as long as the restore) and its contact history: its run goes on as after
a rewind (a settled pile moves by about 0.1 mm in the next step, a tumbling one by 0.3 mm,
and a chaotic run parts from the run it would have had). ``canonical=False`` leaves the
source alone; the restore then goes on as the source would after ``reset_dynamics``.

A clone (a fork, a prediction) is that restore without the plain data: the plan read from
the source is handed to the fresh engine directly, copied where either engine would change
it, so it skips encoding and checking the snapshot (a quarter of a 500-ball board's
restore) and makes the same world through the same calls.
"""

from __future__ import annotations

import copy
import dataclasses
import importlib.metadata
import itertools
from typing import TYPE_CHECKING, Any

from galton.daemon.engines.pybullet import rebuild
from galton.daemon.engines.pybullet.frames import base_offset
from galton.daemon.engines.pybullet.joints import SCALAR
from galton.daemon.engines.pybullet.rebuild import Plan
from galton.daemon.engines.pybullet.snapshot import format as snapformat
from galton.protocol import InvalidArgumentError, OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.engines.pybullet.engine import PybulletEngine


def snapshot(engine: PybulletEngine, canonical: bool) -> dict[str, Any]:
    plan = rebuild.read_plan(engine)
    data = snapformat.encode(plan, engine._values, next_batch(engine),
                             importlib.metadata.version("pybullet"))
    if canonical and engine.bodies:
        rebuild.make_again(engine, plan)
    return data


def restore(engine: PybulletEngine, data: dict[str, Any]) -> None:
    restored = snapformat.decode(data)
    engine._values = restored.params
    engine._batches = itertools.count(restored.next_batch)
    plan = restored.plan
    try:
        rebuild.make_again(engine, plan, lambda: check_made(engine, plan))
    except OperationFailedError as exc:  # a model whose text or meshes fail here
        raise InvalidArgumentError(f"the snapshot cannot be restored here: {exc}") from exc


def clone_into(engine: PybulletEngine, fresh: PybulletEngine) -> PybulletEngine:
    """Make a fresh engine this world as ``restore(snapshot(canonical=False))`` would,
    from the plan itself (closed again if that fails); this world is untouched."""
    try:
        fresh._values = dict(engine._values)
        fresh._batches = itertools.count(next_batch(engine))
        rebuild.make_again(fresh, detached(rebuild.read_plan(engine)))
    except BaseException:
        fresh.close()
        raise
    return fresh


def next_batch(engine: PybulletEngine) -> int:
    """The number the next spawn group or model load takes (the counter keeps it)."""
    number = next(engine._batches)
    engine._batches = itertools.count(number)
    return number


def check_made(engine: PybulletEngine, plan: Plan) -> None:
    """After a snapshot's bodies are made, before its joints are set: every body is
    there, and each articulation fits the model its text made; the roots' inertial
    offsets are read from the bodies made (as a load reads them)."""
    missing = [name for name in plan.bodies if name not in engine.bodies]
    if missing:
        raise InvalidArgumentError(f"the snapshot's model body {missing[0]!r} is not "
                                   "among the bodies its model text makes")
    for root, model in plan.robots.models.items():
        uid = engine.bodies[root].uid
        joints = engine.bodies[root].links
        if len(model.links) != joints or any(
                engine._bc.getJointInfo(uid, j)[2] not in SCALAR for j in model.indices):
            raise InvalidArgumentError(f"the snapshot's joints of model {root!r} do not "
                                       "fit the model its text makes")
    for name, body in engine.bodies.items():
        if body.model is not None and (
                offset := base_offset(engine._bc, body.uid)) is not None:
            plan.frames[name] = offset


def detached(plan: Plan) -> Plan:
    """A copy of a plan read from a live world that another engine can be made from: what
    the new engine keeps and changes later (loaded models' records, articulations with their
    targets, wrenches, states) is copied; the bodies' records are only read (the new engine
    makes its own)."""
    bodies = {name: body if body.model is None else
              dataclasses.replace(body, model=copy.copy(body.model))
              for name, body in plan.bodies.items()}
    states = {name: (list(pose), list(twist)) for name, (pose, twist) in plan.states.items()}
    frames = {name: (position.copy(), turn.copy())
              for name, (position, turn) in plan.frames.items()}
    return Plan(bodies, states, set(plan.exact), copy.deepcopy(plan.robots), frames,
                {root: (q.copy(), qdot.copy()) for root, (q, qdot) in plan.joints.items()})
