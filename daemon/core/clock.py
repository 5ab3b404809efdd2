"""The live world's clock as other threads read it: one immutable value the physics thread
swaps in whole (``SimLoop.refresh_clock``), so a status request on a front's thread never
sees a step from one moment beside a sim time from another."""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

if TYPE_CHECKING:
    from galton.daemon.world.world import World


class WorldClock(NamedTuple):
    """Where the live world is: what a status reply says of its time and contents."""

    step: int
    sim_time: float
    timestep: float
    entity_count: int
    faulted: bool

    @classmethod
    def of(cls, world: World) -> WorldClock:
        """Read now, on the physics thread."""
        return cls(world.step_index, world.sim_time, world.engine.timestep,
                   len(world.entities), world.faulted)


STOPPED_AT_ZERO = WorldClock(0, 0.0, 0.0, 0, False)  # before the first reading
