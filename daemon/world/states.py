"""A world's state kept in memory, for a snapshot slot, a restore or a fork of an unchanged
structure: the engine's own state (``Engine.save_state``) with the World's clock, joint
modes and wrench ends. Loading it needs no rebuild; it is refused (False) when the world's
structure is no longer the one it was kept with (``World.structure``), and the caller then
takes the portable path (daemon/world/snapshot.py)."""

from __future__ import annotations

from dataclasses import dataclass

from galton.daemon.world.world import World
from galton.protocol import JointInfo

# What a kept state costs beside the engine's part, counted against max_snapshot_bytes.
OVERHEAD_BYTES = 256


@dataclass(frozen=True)
class WorldState:
    """One moment of one world's structure."""

    structure: object
    engine: object
    engine_name: str
    step_index: int
    time_base: tuple[int, float, float]
    verified_step: int
    teleported: bool
    joints: dict[str, JointInfo]
    wrench_ends: dict[str, int | None]
    nbytes: int


def save(world: World) -> WorldState | None:
    """The world's state now, or None where its engine keeps none in memory (a faulted
    world's is not worth keeping either: its snapshot takes the portable path)."""
    if world.faulted:
        return None
    kept = world.engine.save_state()
    if kept is None:
        return None
    return WorldState(world.structure, kept, world.engine.name, world.step_index,
                      world._time_base, world.verified_step, world.teleported,
                      dict(world.joints.by_name), dict(world.wrenches.ends),
                      int(getattr(kept, "nbytes", 0)) + OVERHEAD_BYTES)


def fits(world: World, state: WorldState) -> bool:
    """Whether ``state`` loads into ``world`` without a rebuild (the same structure)."""
    return state.structure is world.structure and state.engine_name == world.engine.name


def load(world: World, state: WorldState) -> bool:
    """Set ``world`` to ``state``; False (nothing changed) when its structure changed."""
    if not fits(world, state) or not world.engine.load_state(state.engine):
        return False
    world.step_index, world._time_base = state.step_index, state.time_base
    world.verified_step, world.teleported = state.verified_step, state.teleported
    world.faulted, world.fault_cause = False, ""
    world.joints.by_name = dict(state.joints)
    world.wrenches.ends = dict(state.wrench_ends)
    return True
