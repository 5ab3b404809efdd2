"""A copy of a MuJoCo world in this process, for forks and predictions: no MJCF, no compile,
and until either side changes its structure no copy of the structure either.

A snapshot's restore writes the spec as MJCF, parses and compiles it (about 60 ms for a
500-ball board); a clone shares what is already compiled instead. The fork and its source
share the spec, the compiled model and the records that name spec elements (entities, parked
bodies, the home frame, empty frames awaiting deletion), read-only, and each has its own
data (``mj_copyData`` into a pooled MjData: contacts, warm starts, sleep records, the lot) and
its own small records (parameters, joint targets, wrenches, the sleep guard's memory).

Copy on write: the first change on either side to what they share (a spawn, delete, load,
update, parameters, a teleported static body, joint targets' gains, the sleep guard's
sleep policies, a restore) first takes its own copy (``own``): the spec with
``MjSpec.copy`` (its elements in the same order, with their compiled ids), the model whole
(``mj_copyData``'s twin for models), and the records with every spec element swapped for its
twin in the copied spec. The other holders keep the originals; the last holder copies
nothing. So the two go on independently, and alike: the clone, given the same requests as
its source, gives the same states bit for bit (it is the source's own model, not a
recompile of its spec, so even a world whose pool was edited since its last compile goes
on exactly as the source).
"""

from __future__ import annotations

import copy
import threading
from typing import TYPE_CHECKING, Any

import mujoco

from galton.daemon.engines.mujoco import fast_state
from galton.daemon.engines.mujoco import parked as mp
from galton.daemon.engines.mujoco.entities import Assets, Entity
from galton.daemon.engines.mujoco.wrench import Wrenches
from galton.protocol import OperationFailedError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


class Sharing:
    """The engines holding one spec and model (a source and its forks) until they edit it;
    futures stepped on several threads may each take their copy at once (a lock)."""

    __slots__ = ("holders", "lock")

    def __init__(self) -> None:
        self.holders = 1
        self.lock = threading.Lock()

    def let_go(self) -> bool:
        """One holder fewer; whether others still hold it."""
        with self.lock:
            self.holders -= 1
            return self.holders > 0


def clone(source: MujocoEngine) -> MujocoEngine:
    """A new engine holding a copy of ``source``'s world (see the module docstring)."""
    if source.broken:
        raise OperationFailedError("the MuJoCo world is broken (a failed step or delete); "
                                   "reset it before copying it")
    engine = type(source).__new__(type(source))
    _share_compiled(source, engine)
    _copy_records(source, engine)
    engine.workers = 0  # a new MjData has no thread pool
    engine.start_workers()
    return engine


def own(engine: MujocoEngine) -> None:
    """Before ``engine`` changes its spec, model or the records naming spec elements: its own
    copy of them, unless nobody else holds them (any more)."""
    sharing = engine.sharing
    if sharing is None:
        return
    engine.sharing = None
    if not sharing.let_go():
        return  # the others own theirs already: these are its own
    spec = engine.mj_spec.copy()
    spec.copy_during_attach = True  # (not carried by MjSpec.copy)
    twins = _twins(engine.mj_spec, spec)
    engine.mj_spec = spec
    engine.model = copy.copy(engine.model)
    engine.builders = mp.Builders()
    _copy_spec_records(engine, twins)


def leave(engine: MujocoEngine) -> None:
    """``engine`` is closing: it no longer holds what it shares."""
    sharing = engine.sharing
    if sharing is not None:
        engine.sharing = None
        sharing.let_go()


def _share_compiled(source: MujocoEngine, engine: MujocoEngine) -> None:
    """The spec and compiled model shared, the data copied, and what is kept beside them."""
    if source.sharing is None:
        source.sharing = Sharing()
    with source.sharing.lock:
        source.sharing.holders += 1
    engine.sharing = source.sharing
    engine.values = dict(source.values)
    engine.mj_spec = source.mj_spec
    engine.builders = source.builders  # used only after own(), which makes new ones
    engine.model = source.model
    engine.data = fast_state.data_for(engine.model)
    mujoco.mj_copyData(engine.data, engine.model, source.data)
    engine.xml = source.xml
    engine.parked_edited = source.parked_edited
    engine.broken = False
    engine.diverged, engine.crowded = source.diverged, source.crowded
    engine.steps_since_look = source.steps_since_look
    engine.index = source.index  # frozen, rebuilt (never written) after a compile
    engine.ids = source.ids  # (a spawn from the pool writes it: copied by own)
    engine.watch = None
    engine.warnings = engine.data.warning.number
    engine.sleep_guard = None if source.sleep_guard is None else source.sleep_guard.copy()
    engine.cameras = None  # its own GL context, made by its first render


def _twins(spec: Any, twin: Any) -> dict[int, Any]:
    """Each body and frame of ``spec`` (by ``id`` of its wrapper) -> its twin in the copy
    (``MjSpec.copy`` keeps their order)."""
    out = {id(a): b for a, b in zip(spec.bodies, twin.bodies, strict=True)}
    out.update({id(a): b for a, b in zip(spec.frames, twin.frames, strict=True)})
    return out


def _copy_records(source: MujocoEngine, engine: MujocoEngine) -> None:
    """The records naming spec elements shared (copied by ``own``), the others copied."""
    engine.entities = source.entities
    engine.parts = source.parts
    engine.models = source.models
    engine.empty_frames = source.empty_frames
    engine.parked = source.parked
    engine.loaded_joints = source.loaded_joints.copy()
    engine.wrenches = Wrenches()
    engine.wrenches.held = {n: w.copy() for n, w in source.wrenches.held.items()}


def _copy_spec_records(engine: MujocoEngine, twins: dict[int, Any]) -> None:
    """The records naming spec elements, each element swapped for its twin in the copy."""
    loads: dict[int, Assets] = {}  # a load's Assets are shared by its roots
    engine.entities = {name: _entity(e, twins, loads)
                       for name, e in engine.entities.items()}
    engine.parts = set(engine.parts)
    engine.ids = dict(engine.ids)
    engine.empty_frames = [twins[id(frame)] for frame in engine.empty_frames]
    pool = mp.ParkedBodies()
    pool._serial = engine.parked._serial
    pool._parked = {key: [twins[id(b)] for b in bodies]
                    for key, bodies in engine.parked._parked.items()}
    engine.parked = pool


def _entity(e: Entity, twins: dict[int, Any], loads: dict[int, Assets]) -> Entity:
    """A copy of every field (``dataclasses.replace`` took 4 µs an entity, this 1), with
    the body's twin and the load's copied Assets."""
    twin: Entity = object.__new__(Entity)
    twin.__dict__.update(e.__dict__)
    twin.body = twins[id(e.body)]
    if e.assets is not None:
        twin.assets = loads.setdefault(id(e.assets), Assets(set(e.assets.names),
                                                            e.assets.roots))
    return twin
