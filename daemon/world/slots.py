"""Named snapshot slots: a daemon's snapshots of its worlds, within the limits on their
number and total size.

A slot keeps a portable blob (msgpack, daemon/world/snapshot.py) or, where the engine keeps
its state in memory (``Engine.save_state``), that state (daemon/world/states.py): taken and
restored without a rebuild while the world's structure stays the same. Such a slot also
holds a twin of the world at that structure (one per structure, shared by its slots, made by
the first snapshot of it), so that it can still be restored after the world's structure
changed, into another world, or predicted from: the twin takes the state, and is forked.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from galton.daemon.core.limits import Limits
from galton.daemon.world import states
from galton.daemon.world.snapshot import clone_of
from galton.daemon.world.world import World
from galton.protocol import NotFoundError, ResourceLimitError
from galton.protocol.errors import brief, did_you_mean


@dataclass(frozen=True)
class Slot:
    """One kept snapshot and what it is of: a blob, a kept state, or both."""

    name: str
    world: str
    engine: str
    blob: bytes | None
    step: int
    sim_time: float
    entity_count: int
    state: states.WorldState | None = None

    @property
    def size(self) -> int:
        """Bytes it holds: its blob's, or its kept state's."""
        if self.blob is not None:
            return len(self.blob)
        return 0 if self.state is None else self.state.nbytes

    def to_wire(self) -> dict[str, object]:
        return {"slot": self.name, "world": self.world, "engine": self.engine,
                "bytes": self.size, "step": self.step, "sim_time": self.sim_time,
                "entity_count": self.entity_count}


class SnapshotSlots:
    """Slots by name, refusing to pass ``max_snapshots`` or ``max_snapshot_bytes``; and the
    twins their kept states load into (by structure)."""

    def __init__(self, limits: Limits) -> None:
        self.limits = limits
        self.by_name: dict[str, Slot] = {}
        self.twins: dict[object, World] = {}

    def keep(self, slot: Slot, source: World | None = None) -> None:
        """Keep ``slot`` (replacing one of its name); ``source``: the world a kept state is
        of, twinned now if no slot holds its structure yet."""
        others = {n: s for n, s in self.by_name.items() if n != slot.name}
        if len(others) + 1 > self.limits.max_snapshots:
            raise ResourceLimitError(
                f"the daemon holds {len(others)} snapshot slots, its limit "
                f"(galton-daemon --limit max_snapshots=N); delete one first",
                {"limit": "max_snapshots", "max": self.limits.max_snapshots})
        total = sum(s.size for s in others.values()) + slot.size
        if total > self.limits.max_snapshot_bytes:
            raise ResourceLimitError(
                f"snapshot slots would hold {total} bytes; at most "
                f"{self.limits.max_snapshot_bytes}",
                {"limit": "max_snapshot_bytes", "max": self.limits.max_snapshot_bytes})
        state = slot.state
        if state is not None and slot.blob is None and state.structure not in self.twins:
            assert source is not None and source.structure is state.structure
            self.twins[state.structure] = clone_of(source, f"{source.name}:twin", self.limits)
        replaced = self.by_name.get(slot.name)
        self.by_name[slot.name] = slot
        self._drop_unused_twins()
        if replaced is not None and replaced.state is not None and source is not None \
                and replaced.state.engine_name == source.engine.name:
            source.engine.recycle_state(replaced.state.engine)

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
        self._drop_unused_twins()

    def twin_at(self, slot: Slot) -> World:
        """The twin of the slot's structure, set to its kept state: fork it, never step it."""
        state = slot.state
        assert state is not None and slot.blob is None
        twin = self.twins[state.structure]
        if not states.load(twin, state):
            raise AssertionError("a slot's twin refused its own structure's state")
        return twin

    def world_of(self, slot: Slot, name: str, decoded: Callable[[bytes], World]) -> World:
        """A new world of the slot's moment: a fork of its twin, or ``decoded`` from its
        blob (the portable path)."""
        if slot.blob is not None:
            return decoded(slot.blob)
        return clone_of(self.twin_at(slot), name, self.limits)

    def close(self) -> None:
        """Release every twin's engine (the daemon is closing)."""
        for twin in self.twins.values():
            twin.engine.close()
        self.twins.clear()

    def _drop_unused_twins(self) -> None:
        used = {s.state.structure for s in self.by_name.values()
                if s.state is not None and s.blob is None}
        for structure in [k for k in self.twins if k not in used]:
            self.twins.pop(structure).engine.close()
