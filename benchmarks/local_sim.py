"""The subset of ``Client`` a bench trial uses, served by the daemon's own World in this process.

A trial run on it is bit-identical to the same trial through a daemon
(``benchmarks/bridge_overhead.py`` checks that), so in-process runs stand for bridge runs:
the bridge benchmarks compare the two, and ``research/fidelity_inprocess.py`` and
``research/ab_trials.py`` run many trials without Zenoh.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from typing import Any

from galton.client.sdk.client import Stamp, States
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import BodyGroup, Capabilities, SimStatus


class LocalSim:
    """The subset of ``Client`` a trial uses, served by a World in this process."""

    def __init__(self) -> None:
        self.world: World | None = None

    @contextlib.contextmanager
    def on_telemetry(self, callback: Any) -> Iterator[None]:
        yield None

    def load_world(self, engine: str, params: dict[str, Any] | None = None) -> None:
        if self.world is not None:
            self.world.engine.close()
        self.world = World(create_engine(engine))
        if params:
            self.world.engine.set_params(params)

    def spawn(self, *groups: BodyGroup, timeout: float | None = None) -> list[str]:
        """Through the wire encoding, as the daemon sees them (quaternions normalised the
        same way), so that both sides simulate bit-identical worlds."""
        assert self.world is not None
        return self.world.spawn([BodyGroup.from_wire(g.to_wire()) for g in groups])

    def run_until(self, sim_time: float, timeout: float | None = None) -> Stamp:
        assert self.world is not None
        dt = self.world.engine.timestep
        self.world.step(math.ceil((sim_time - self.world.sim_time) / dt - 1e-9))
        return Stamp(self.world.step_index, self.world.sim_time)

    def run_until_rest(self, sim_time: float, names: list[str], speed: float,
                       every: float, timeout: float | None = None) -> tuple[States, bool]:
        """The daemon's until_rest loop: step to each check, read, stop once all rest."""
        assert self.world is not None
        dt = self.world.engine.timestep
        total = math.ceil((sim_time - self.world.sim_time) / dt - 1e-9)
        every_steps, done = max(1, round(every / dt)), 0
        while True:
            count = min(total - done, every_steps - done % every_steps)
            self.world.step(count)
            done += count
            states = self.get_states(names)
            at_rest = bool((states.speeds < speed).all())
            if at_rest or done == total:
                return states, at_rest

    def get_states(self, names: list[str]) -> States:
        assert self.world is not None
        poses, twists = self.world.get_states(names)
        return States(list(names), poses, twists, self.world.step_index, self.world.sim_time)

    def status(self) -> SimStatus:
        assert self.world is not None
        return SimStatus("paused", self.world.step_index, self.world.sim_time,
                         self.world.engine.timestep, 0.0, 0.0, len(self.world.entities),
                         self.world.engine.name, "local")

    def get_params(self) -> dict[str, Any]:
        assert self.world is not None
        return self.world.engine.get_params()

    def capabilities(self) -> Capabilities:
        assert self.world is not None
        return self.world.engine.capabilities()
