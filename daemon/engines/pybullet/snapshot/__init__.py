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
from typing import TYPE_CHECKING, Any, TypeVar

from pybullet_utils.bullet_client import BulletClient

from galton.daemon.engines.pybullet.frames import Offset, base_offset
from galton.daemon.engines.pybullet.joints import SCALAR
from galton.daemon.engines.pybullet.rebuild import Body, Plan
from galton.daemon.engines.pybullet.snapshot import format as snapformat
from galton.protocol import InvalidArgumentError, OperationFailedError

if TYPE_CHECKING:
    from collections.abc import Callable

    from galton.daemon.engines.pybullet.robots import Robots

_Fresh = TypeVar("_Fresh", bound="Snapshots")


class Snapshots:
    """The engine's part that takes and restores snapshots (mixed into PybulletEngine)."""

    _bc: BulletClient
    bodies: dict[str, Body]
    _values: dict[str, Any]
    _batches: itertools.count[int]
    robots: Robots
    frames: dict[str, Offset]

    if TYPE_CHECKING:
        def _plan(self) -> Plan: ...
        def _make_again(self, plan: Plan, check: Callable[[], None] | None = None) -> None: ...
        def close(self) -> None: ...

    def _snapshot(self, canonical: bool) -> dict[str, Any]:
        plan = self._plan()
        data = snapformat.encode(plan, self._values, self._next_batch(),
                                 importlib.metadata.version("pybullet"))
        if canonical and self.bodies:
            self._make_again(plan)
        return data

    def _restore(self, data: dict[str, Any]) -> None:
        restored = snapformat.decode(data)
        self._values = restored.params
        self._batches = itertools.count(restored.next_batch)
        plan = restored.plan
        try:
            self._make_again(plan, lambda: self._check_made(plan))
        except OperationFailedError as exc:  # a model whose text or meshes fail here
            raise InvalidArgumentError(f"the snapshot cannot be restored here: {exc}") from exc

    def _clone_into(self, fresh: _Fresh) -> _Fresh:
        """Make a fresh engine this world as ``restore(snapshot(canonical=False))`` would,
        from the plan itself (closed again if that fails); this world is untouched."""
        try:
            fresh._values = dict(self._values)
            fresh._batches = itertools.count(self._next_batch())
            fresh._make_again(detached(self._plan()))
        except BaseException:
            fresh.close()
            raise
        return fresh

    def _next_batch(self) -> int:
        """The number the next spawn group or model load takes (the counter keeps it)."""
        number = next(self._batches)
        self._batches = itertools.count(number)
        return number

    def _check_made(self, plan: Plan) -> None:
        """After a snapshot's bodies are made, before its joints are set: every body is
        there, and each articulation fits the model its text made; the roots' inertial
        offsets are read from the bodies made (as a load reads them)."""
        missing = [name for name in plan.bodies if name not in self.bodies]
        if missing:
            raise InvalidArgumentError(f"the snapshot's model body {missing[0]!r} is not "
                                       "among the bodies its model text makes")
        for root, model in plan.robots.models.items():
            uid = self.bodies[root].uid
            joints = self.bodies[root].links
            if len(model.links) != joints or any(
                    self._bc.getJointInfo(uid, j)[2] not in SCALAR for j in model.indices):
                raise InvalidArgumentError(f"the snapshot's joints of model {root!r} do not "
                                           "fit the model its text makes")
        for name, body in self.bodies.items():
            if body.model is not None and (
                    offset := base_offset(self._bc, body.uid)) is not None:
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
