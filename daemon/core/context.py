"""What a handler may reach of the core: ``OpContext``, the narrow face of the physics loop
that every operation's handler receives (``handler(ctx, call, request) -> Result``).

``SimLoop`` (daemon/core/loop.py) satisfies it structurally; handlers import this module,
never the loop, so there is no import cycle (loop -> handlers -> time control -> loop).
Everything here is used on the physics thread only.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from galton.daemon.access.lease import Lease
    from galton.daemon.core.calls import Call, StepJob
    from galton.daemon.core.limits import Limits
    from galton.daemon.core.monitor import Pacer, RtfWindow
    from galton.daemon.core.step_queue import StepQueue
    from galton.daemon.world.scene import World
    from galton.daemon.world.slots import SnapshotSlots
    from galton.daemon.world.state_streams import StateStreams
    from galton.protocol import RemoteError, SimState, SimStatus
    from galton.protocol.requests import Args


class OpContext(Protocol):
    """The worlds, the clock and its state machine, the one step job, control, limits."""

    # The worlds: the live one, side worlds by name, snapshot slots and how engines are made.
    world: World
    side: dict[str, World]
    slots: SnapshotSlots
    snapshot_key: bytes | None
    engine_factory: Callable[[str], Any] | None
    # Time: the state machine, pacing and the step job (started and ended by ``start_job``
    # and ``end_job`` only).
    state: SimState
    target_rtf: float
    rtf: float
    pacer: Pacer
    rtf_window: RtfWindow
    job: StepJob | None
    step_queue: StepQueue  # step requests waiting for the job, handled when it ends
    # Who may do what, and how much.
    lease: Lease
    limits: Limits
    instance: str
    advertised: dict[str, Any]
    client_alive: Callable[[str], bool] | None
    streams: StateStreams

    def world_for(self, args: dict[str, Any] | Args) -> World:
        """The world a request names (the live one when it names none), or NOT_FOUND."""

    def set_state(self, state: SimState) -> None:
        """Change the simulation state and announce it."""

    def status(self) -> SimStatus:
        """The status reply's values now."""

    def emit(self, event: dict[str, Any]) -> None:
        """Publish an event to every front."""

    def refresh_clock(self) -> None:
        """Take the world's clock into the atomic status snapshot."""

    def tune_switch_interval(self) -> None:
        """Set Python's switch interval for the live world's engine."""

    def start_job(self, job: StepJob) -> None:
        """Make ``job`` the step job (there is at most one)."""

    def end_job(self) -> StepJob | None:
        """End the step job, if any, and return it (its caller answers it)."""

    def finish_job(self, job: StepJob) -> None:
        """Answer a step job that has done its steps."""

    def check_job_reads(self) -> None:
        """Answer the step job now if an entity it reads is gone."""

    def reply_error(self, call: Call, error: RemoteError) -> None:
        """Answer ``call`` with ``error``."""
