"""What a handler may reach of the core: small Protocols, one per part of the physics loop
(the worlds, the clock, the step job, access, streams), and, per handler family, the
narrowest union of them it needs. ``OpContext`` is all of them: what the dispatcher holds
and passes (``handler(ctx, call, request) -> Result``); a handler typed with a narrower
context takes it (mypy --strict holds that a family reaches nothing else).

``SimLoop`` (daemon/core/loop.py) satisfies them structurally; handlers import this module,
never the loop, so there is no import cycle (loop -> handlers -> time control -> loop).
Everything here is used on the physics thread only. What the loop was given at
construction (``core/wiring.py``: instance, limits, snapshot key, engine factory, advertised,
client liveness) is read-only here. docs/ARCHITECTURE.md lists which family sees what.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from galton.daemon.access.lease import Lease
    from galton.daemon.core.calls import StepJob
    from galton.daemon.core.limits import Limits
    from galton.daemon.core.monitor import Pacer, RtfWindow
    from galton.daemon.core.replies import Replies
    from galton.daemon.core.step_queue import StepQueue
    from galton.daemon.world.slots import SnapshotSlots
    from galton.daemon.world.state_streams import StateStreams
    from galton.daemon.world.world import World
    from galton.protocol import SimState, SimStatus
    from galton.protocol.requests import Args


class Events(Protocol):
    """Publishing to every front."""

    def emit(self, event: dict[str, Any]) -> None:
        """Publish an event to every front."""


class WorldChoice(Protocol):
    """Which world a request names."""

    def world_for(self, args: dict[str, Any] | Args) -> World:
        """The world a request names (the live one when it names none), or NOT_FOUND."""


class Worlds(WorldChoice, Events, Protocol):
    """The worlds: the live one, side worlds by name, snapshot slots, how engines are made,
    and the daemon's limits on them."""

    world: World
    side: dict[str, World]
    slots: SnapshotSlots

    @property
    def snapshot_key(self) -> bytes | None: ...

    @property
    def engine_factory(self) -> Callable[[str], Any] | None: ...

    @property
    def limits(self) -> Limits: ...


class Clock(Protocol):
    """Time: the state machine and pacing of the live world."""

    state: SimState
    target_rtf: float
    rtf: float
    pacer: Pacer
    rtf_window: RtfWindow

    def set_state(self, state: SimState) -> None:
        """Change the simulation state and announce it."""

    def status(self) -> SimStatus:
        """The status reply's values now."""

    def refresh_clock(self) -> None:
        """Take the world's clock into the status values (read at once by status)."""

    def tune_switch_interval(self) -> None:
        """Set Python's switch interval for the live world's engine."""


class JobEnd(Protocol):
    """The one step job as its runners see it: the world it steps, ending and answering it."""

    world: World
    job: StepJob | None

    def end_job(self) -> StepJob | None:
        """End the step job, if any, and return it (its caller answers it)."""

    replies: Replies  # answering a call (daemon/core/replies.py)

    def finish_job(self, job: StepJob) -> None:
        """Answer a step job that has done its steps."""


class Jobs(JobEnd, Protocol):
    """The one step job (started and ended by ``start_job`` and ``end_job`` only) and the
    step requests waiting for it."""

    step_queue: StepQueue

    def start_job(self, job: StepJob) -> None:
        """Make ``job`` the step job (there is at most one)."""

    def check_job_reads(self) -> None:
        """Answer the step job now if an entity it reads is gone."""


class SceneContext(WorldChoice, Events, Protocol):
    """What a scene operation's wrapper sees (daemon/ops/handlers.py ``_scene``): the world
    named, events, and the step job's reads."""

    def check_job_reads(self) -> None:
        """Answer the step job now if an entity it reads is gone."""


class CapabilitiesContext(WorldChoice, Protocol):
    """``capabilities``: the world named and what the daemon advertises."""

    @property
    def advertised(self) -> dict[str, Any]: ...


class AccessContext(Events, Protocol):
    """Who controls the daemon (daemon/access/lease.py)."""

    lease: Lease

    @property
    def client_alive(self) -> Callable[[str], bool | None] | None: ...


class StreamContext(WorldChoice, Protocol):
    """State streams (daemon/world/state_streams.py): the worlds they sample, the clock's
    state and rate they report, and whether their owner is still there."""

    world: World
    side: dict[str, World]
    state: SimState
    rtf: float
    streams: StateStreams

    @property
    def instance(self) -> str: ...

    @property
    def client_alive(self) -> Callable[[str], bool | None] | None: ...

    @property
    def limits(self) -> Limits: ...


class PredictContext(Worlds, Jobs, Protocol):
    """``predict``: a copy of a world stepped as the step job."""


class WorldsContext(Worlds, Clock, Jobs, Protocol):
    """Creating, forking, deleting and loading worlds: loading the live one re-anchors the
    clock, deleting one ends the job that steps it."""


class TimeContext(Worlds, Clock, Jobs, Protocol):
    """Time control (daemon/core/time_control.py): the clock, the step job, and the status
    reply's instance and controller."""

    lease: Lease

    @property
    def instance(self) -> str: ...


class OpContext(TimeContext, AccessContext, StreamContext, CapabilitiesContext, Protocol):
    """Every part: what the dispatcher passes to every handler (``SimLoop`` implements it)."""
