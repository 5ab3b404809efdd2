"""Spawning into the MuJoCo world, as functions of the engine.

A spawn binds the names to parked, pre-compiled bodies where the pool holds enough of a
group's kind: no compile (``parked``). The other groups are added to the spec, with spare
parked twins, and compiled in one recompile that keeps the state of the bodies already there.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.mujoco import parked as mp
from galton.daemon.engines.mujoco import state as mst
from galton.daemon.engines.mujoco.entities import WORLD, Entity
from galton.protocol import BodyGroup, InvalidArgumentError, NameNotUniqueError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def spawn(engine: MujocoEngine, groups: Sequence[BodyGroup]) -> None:
    """Bind parked bodies where the pool has enough of a group's kind; compile the other
    groups (with spare parked twins) in one recompile."""
    check_new(engine, [n for g in groups for n in g.names])
    pooled, compiled = engine.parked.plan(groups, engine.values, engine.model.nbody,
                                         len(engine.entities), engine.free_bodies())
    if compiled:
        compile_groups(engine, compiled)
    for group, key in pooled:
        bind(engine, group, key)
    if pooled:
        mp.refresh(engine.model, engine.data)
    for group in groups:
        if group.twists is not None and not group.static:
            mst.write_twists(engine.data, engine.index, engine.body_ids(group.names),
                             np.asarray(group.twists, dtype=float), None)


def check_new(engine: MujocoEngine, names: Sequence[str]) -> None:
    """Refuse repeated names, names in use, and the names the engine keeps for itself."""
    if len(set(names)) != len(names):
        raise InvalidArgumentError("MuJoCo rejected the change: a name is repeated")
    for name in names:
        if name in engine.entities:  # a model's links are entities too
            raise NameNotUniqueError(f"an entity named {name!r} already exists")
        if name == WORLD or name.startswith(mp.PREFIX):
            raise InvalidArgumentError(f"the body name {name!r} is the MuJoCo engine's own "
                                       f"(the world, or beginning {mp.PREFIX!r})")


def compile_groups(engine: MujocoEngine, compiled: Sequence[mp.Planned]) -> None:
    """Add the groups' bodies and spares, recompile; on any failure take them out."""
    snapshot = engine.parked.snapshot()
    additions = mp.Additions(engine.mj_spec, engine.builders)
    nbody, nv = engine.model.nbody, engine.model.nv
    try:
        for group, material, _, spares in compiled:
            additions.add(group, material)
            if spares:
                additions.add(engine.parked.spare_group(group, spares), material, parked=True)
            nbody += len(group) + spares
            nv += 0 if group.static else 6 * (len(group) + spares)
        engine.compile(nbody, nv)
    except BaseException:
        engine.parked.restore(snapshot)
        additions.undo()
        raise
    made = iter(additions.bodies())
    engine.empty_frames += additions.empty_frames
    for group, _, key, spares in compiled:
        for name, body in zip(group.names, next(made), strict=True):
            engine.entities[name] = Entity(body, group.static, friction=group.friction,
                                            restitution=group.restitution, key=key)
        if spares and key is not None:
            engine.parked.adopt(key, next(made))
    engine.reindex()


def bind(engine: MujocoEngine, group: BodyGroup, key: mp.Key) -> None:
    """Give a group's names to parked bodies of its kind and release them: no compile."""
    bodies = engine.parked.take(key, len(group))
    poses = np.asarray(group.poses, dtype=float)
    mp.bind_spec(bodies, group.names, poses)
    for name, body in zip(group.names, bodies, strict=True):
        engine.entities[name] = Entity(body, group.static, friction=group.friction,
                                        restitution=group.restitution, key=key)
        engine.ids[name] = body.id
    engine.watch = None
    engine.parked_edited = True
    mp.bind_arrays(engine.model, engine.data, engine.index, engine.body_ids(group.names),
                   poses)
