"""Named snapshot slots: a daemon's snapshots of its worlds, kept as msgpack blobs within
the limits on their number and total size."""

from __future__ import annotations

from dataclasses import dataclass

from galton.daemon.core.limits import Limits
from galton.protocol import NotFoundError, ResourceLimitError
from galton.protocol.errors import brief, did_you_mean


@dataclass(frozen=True)
class Slot:
    """One kept snapshot and what it is of."""

    name: str
    world: str
    engine: str
    blob: bytes
    step: int
    sim_time: float
    entity_count: int

    def to_wire(self) -> dict[str, object]:
        return {"slot": self.name, "world": self.world, "engine": self.engine,
                "bytes": len(self.blob), "step": self.step, "sim_time": self.sim_time,
                "entity_count": self.entity_count}


class SnapshotSlots:
    """Slots by name, refusing to pass ``max_snapshots`` or ``max_snapshot_bytes``."""

    def __init__(self, limits: Limits) -> None:
        self.limits = limits
        self.by_name: dict[str, Slot] = {}

    def keep(self, slot: Slot) -> None:
        others = {n: s for n, s in self.by_name.items() if n != slot.name}
        if len(others) + 1 > self.limits.max_snapshots:
            raise ResourceLimitError(
                f"the daemon holds {len(others)} snapshot slots, its limit "
                f"(galton-daemon --limit max_snapshots=N); delete one first",
                {"limit": "max_snapshots", "max": self.limits.max_snapshots})
        total = sum(len(s.blob) for s in others.values()) + len(slot.blob)
        if total > self.limits.max_snapshot_bytes:
            raise ResourceLimitError(
                f"snapshot slots would hold {total} bytes; at most "
                f"{self.limits.max_snapshot_bytes}",
                {"limit": "max_snapshot_bytes", "max": self.limits.max_snapshot_bytes})
        self.by_name[slot.name] = slot

    def get(self, name: str) -> Slot:
        found = self.by_name.get(name)
        if found is None:
            raise NotFoundError(f"no snapshot slot named {brief(name)}"
                                f"{did_you_mean(name[:64], self.by_name)}",
                                {"slots": sorted(self.by_name)[:100]})
        return found

    def delete(self, name: str) -> None:
        self.get(name)
        del self.by_name[name]
