"""Several worlds per daemon, and snapshots of them: list_worlds, create_world, fork_world,
delete_world, snapshot, restore, snapshots, delete_snapshot (docs/protocol.md, "Worlds").

The live world plays; side worlds move only by step requests, run after the live world's
due steps (daemon/core/side_jobs.py). A world replaced by a restore is rebuilt on a fresh
engine first, so a refused snapshot leaves it as it was.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from galton.daemon.core import time_control
from galton.daemon.core.calls import Call
from galton.daemon.core.context import WorldsContext
from galton.daemon.core.reply_limit import require_room
from galton.daemon.ops.binding import handles
from galton.daemon.world import states
from galton.daemon.world.slots import Slot
from galton.daemon.world.snapshot import clone_of, decode, encode, snapshot_of, world_from
from galton.daemon.world.world import World
from galton.protocol import (
    InvalidArgumentError,
    NameNotUniqueError,
    OperationFailedError,
    ResourceLimitError,
    SimState,
)
from galton.protocol import requests as rq
from galton.protocol.errors import brief
from galton.protocol.vocabulary import MAX_WORLD_NAME

if TYPE_CHECKING:
    from galton.daemon.engines.base import Engine



def world_row(ctx: WorldsContext, world: World) -> dict[str, Any]:
    live = world is ctx.world
    state = ctx.state if live else (SimState.STOPPED if world.step_index == 0
                                     else SimState.PAUSED)
    return {"name": world.name, "live": live, "engine": world.engine.name,
            "state": state.value, "step": world.step_index, "sim_time": world.sim_time,
            "entity_count": len(world.entities), "faulted": world.faulted}


@handles("list_worlds")
def list_worlds(ctx: WorldsContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return {"worlds": [world_row(ctx, w) for w in (ctx.world, *ctx.side.values())]}


def _new_name(ctx: WorldsContext, name: str, where: str) -> str:
    if not name.isprintable():  # its length is declared (protocol/requests.py)
        raise InvalidArgumentError(f"{where}.name {brief(name)} must be 1-{MAX_WORLD_NAME} "
                                   "printable characters")
    if name == ctx.world.name or name in ctx.side:
        raise NameNotUniqueError(f"a world named {name!r} exists; delete it first")
    if 1 + len(ctx.side) >= ctx.limits.max_worlds:
        raise ResourceLimitError(
            f"the daemon holds {1 + len(ctx.side)} worlds, its limit (galton-daemon "
            "--limit max_worlds=N)", {"limit": "max_worlds", "max": ctx.limits.max_worlds})
    return name


def _factory(ctx: WorldsContext) -> Any:
    if ctx.engine_factory is None:
        raise OperationFailedError("this daemon cannot make engines")
    return ctx.engine_factory


@handles("create_world")
def create_world(ctx: WorldsContext, call: Call, request: rq.CreateWorld) -> dict[str, Any]:
    name = _new_name(ctx, request.name, "create_world")
    kind = request.engine or ctx.world.engine.name
    params = request.params
    engine: Engine = _factory(ctx)(kind)
    try:
        if params:
            engine.set_params(params)
    except Exception:
        engine.close()
        raise
    ctx.side[name] = World(engine, name, ctx.limits)
    ctx.emit({"kind": "world", "op": "create_world", "world": name})
    return world_row(ctx, ctx.side[name])


@handles("fork_world")
def fork_world(ctx: WorldsContext, call: Call, request: rq.ForkWorld) -> dict[str, Any]:
    name = _new_name(ctx, request.name, "fork_world")
    source = ctx.world_for({"world": request.source})
    source.verify()
    ctx.side[name] = clone_of(source, name, ctx.limits)
    ctx.emit({"kind": "world", "op": "fork_world", "world": name, "source": source.name})
    return world_row(ctx, ctx.side[name])


@handles("delete_world")
def delete_world(ctx: WorldsContext, call: Call, request: rq.Named) -> dict[str, Any]:
    name = request.name
    world = ctx.world_for({"world": name})
    if world is ctx.world:
        raise InvalidArgumentError("the live world cannot be deleted (load_world replaces it)")
    if ctx.job is not None and ctx.job.world is world:
        time_control.cancel_job(ctx, "its world was deleted")
    del ctx.side[name]
    world.engine.close()
    ctx.emit({"kind": "world", "op": "delete_world", "world": name})
    return {"count": 1}


@handles("snapshot")
def snapshot(ctx: WorldsContext, call: Call, request: rq.Snapshot) -> dict[str, Any]:
    world = ctx.world_for(request)
    slot_name = request.slot
    want_blob = request.blob
    if slot_name is None and not want_blob:
        raise InvalidArgumentError("snapshot needs a 'slot' to keep it in, 'blob': true to "
                                   "return it, or both")
    if slot_name is not None and not slot_name.isprintable():  # its length is declared
        raise InvalidArgumentError(f"snapshot.slot {brief(slot_name)} must be "
                                   f"1-{MAX_WORLD_NAME} printable characters")
    world.verify()
    state = None if slot_name is None else states.save(world)
    blob = None
    if want_blob or state is None:
        blob = encode(snapshot_of(world), ctx.snapshot_key)
    if want_blob:  # checked before a slot is kept: a refused request changes nothing
        assert blob is not None
        require_room("this snapshot's blob", len(blob), ctx.limits.max_reply_bytes,
                     "keep it in a slot without 'blob'")
    kept = Slot(slot_name or "", world.name, world.engine.name, blob, world.step_index,
                world.sim_time, len(world.entities), state)
    if slot_name is not None:
        ctx.slots.keep(kept, world)
    result = {**kept.to_wire(), "slot": slot_name}
    if want_blob:
        result["blob"] = blob
    return result


@handles("restore")
def restore(ctx: WorldsContext, call: Call, request: rq.Restore) -> dict[str, Any]:
    """A slot kept as a state goes back into its own structure in place (no rebuild);
    anything else builds a new world, so a refused snapshot leaves the world as it was."""
    world = ctx.world_for(request)
    slot_name, blob = request.slot, request.blob
    if (slot_name is None) == (blob is None):
        raise InvalidArgumentError("restore needs exactly one of 'slot' or 'blob'")
    slot = None if slot_name is None else ctx.slots.get(slot_name)
    if slot is not None and slot.state is not None and states.load(world, slot.state):
        _restored(ctx, world, world)
        return world_row(ctx, world)
    if slot is not None:
        _require_engine(slot.engine, world)
        new = ctx.slots.world_of(slot, world.name, lambda raw: _decoded(ctx, raw, world))
    else:
        new = _decoded(ctx, blob, world)
    _restored(ctx, world, new)
    return world_row(ctx, new)


def _require_engine(kind: str, world: World) -> None:
    if kind != world.engine.name:
        raise InvalidArgumentError(f"the snapshot is of engine {brief(kind)}; this world "
                                   f"runs {world.engine.name}: restore it into a world of "
                                   "its engine")


def _decoded(ctx: WorldsContext, blob: Any, world: World) -> World:
    """A new world rebuilt from a blob, for ``world`` (whose engine it must be of)."""
    data = decode(blob, ctx.limits, ctx.snapshot_key)
    return world_from(data, _factory(ctx), world.name, ctx.limits, world.engine.name)


def _restored(ctx: WorldsContext, world: World, new: World) -> None:
    """``new`` (``world`` itself, set in place, or its replacement) takes ``world``'s place:
    its job is ended, the live clock re-anchored."""
    if ctx.job is not None and (ctx.job.world or ctx.world) is world:
        time_control.cancel_job(ctx, "its world was restored")
    if world is ctx.world:
        ctx.world = new
        ctx.tune_switch_interval()
        ctx.refresh_clock()
        ctx.rtf_window.clear()
        ctx.pacer.anchor(time.monotonic(), new.sim_time, ctx.target_rtf)
    else:
        ctx.side[world.name] = new
    if new is not world:
        world.engine.close()
    ctx.emit({"kind": "scene", "op": "restore", "world": new.name, "step": new.step_index})


@handles("snapshots")
def snapshots(ctx: WorldsContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return {"slots": [slot.to_wire() for slot in ctx.slots.by_name.values()]}


@handles("delete_snapshot")
def delete_snapshot(ctx: WorldsContext, call: Call, request: rq.Slot) -> dict[str, Any]:
    ctx.slots.delete(request.slot)
    return {"count": 1}
