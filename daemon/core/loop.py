"""The physics thread: applies requests between steps, paces the clock, publishes telemetry.

Everything that touches the engine runs here, on one thread (galton-daemon's main thread;
``Daemon.start`` gives it a thread of its own when embedded). The fronts only hand ``Call``
objects to the loop's intake (daemon/core/inbox.py); this loop answers each of them exactly
once. What it does not need to own is its collaborators': the steps (core/stepping.py),
status and telemetry (core/loop_status.py), replies (core/replies.py).
"""

from __future__ import annotations

import logging
import math
import queue
import sys
import time
from collections.abc import Callable
from contextlib import nullcontext
from typing import Any

import msgpack

from galton.daemon.access import lease
from galton.daemon.access.zmq_auth import refuse_by_role
from galton.daemon.core import job_results, time_control
from galton.daemon.core.calls import EVENTS, Call, StepJob, Task
from galton.daemon.core.inbox import Intake
from galton.daemon.core.limits import Limits, decode_limits
from galton.daemon.core.loop_status import StatusBoard
from galton.daemon.core.monitor import Pacer, RtfWindow
from galton.daemon.core.replies import Replies
from galton.daemon.core.step_queue import StepBusyError, StepQueue
from galton.daemon.core.stepping import Stepping
from galton.daemon.core.wiring import LoopWiring
from galton.daemon.ops.handlers import HANDLERS
from galton.daemon.world.slots import SnapshotSlots
from galton.daemon.world.state_streams import StateStreams
from galton.daemon.world.world import World
from galton.protocol import (
    NotFoundError,
    OperationFailedError,
    PhysicsError,
    RemoteError,
    SimState,
    SimStatus,
    decode_request,
)
from galton.protocol.errors import brief, did_you_mean
from galton.protocol.operations import operation
from galton.protocol.requests import Args

log = logging.getLogger("galton.daemon")

# Python's switch interval while the engine holds the GIL as it steps (PyBullet): short, so
# status requests on Zenoh's threads get in between steps. A waiting thread asks for the GIL
# only after this long and then waits for the step to end: under load, status p50 is 9 ms
# at the default 5 ms, 1.4 ms at 0.5 ms and 0.84 ms at 0.05 ms, with no measurable cost to
# the trial. An engine that releases the GIL (MuJoCo) keeps the default, which runs its
# trials 2-3 % faster (docs/PERFORMANCE.md).
SHORT_SWITCH_INTERVAL_S = 0.00005
DEFAULT_SWITCH_INTERVAL_S = 0.005
# Physics before requests: while steps are due now (a step job, RTF 0, a world behind its
# clock), requests get at most this much of the physics thread between two chunks of steps
# (a chunk is stepping.CHUNK_WALL_S), and always at least one request, so neither side starves.
REQUEST_SLICE_S = 0.001


class SimLoop:
    """Owns the World and the simulation state machine (stopped / playing / paused)."""

    def __init__(self, world: World, wiring: LoopWiring) -> None:
        self.world = world
        self.wiring = wiring  # frozen: nothing rewires a loop once it is built
        limits = wiring.limits
        self.decode_limits = decode_limits(limits)
        self.state = SimState.STOPPED
        self.target_rtf = 1.0
        self.job: StepJob | None = None
        self.step_queue = StepQueue()  # step requests waiting for the job (step_queue.py)
        self.lease = lease.Lease()  # who holds control (daemon/access/lease.py)
        self.pacer = Pacer()
        self.rtf_window = RtfWindow()
        self.rtf = 0.0  # measured at each telemetry sample
        # stream_states (daemon/world/state_streams.py): samples go to every front.
        self.streams = StateStreams(wiring.publish)
        self.side: dict[str, World] = {}  # side worlds by name (daemon/ops/worlds.py)
        self._next_checkpoint = (time.monotonic() + wiring.checkpoints.period_s
                                 if wiring.checkpoints is not None else math.inf)
        self.slots = SnapshotSlots(limits)
        self.stepping = Stepping(self)  # the live world's steps (daemon/core/stepping.py)
        # Status on any thread, telemetry (daemon/core/loop_status.py); replies from this one.
        self.status_board = StatusBoard(self, wiring.publish, wiring.telemetry_rate_hz,
                                        self.decode_limits)
        self.replies = Replies(self, limits.max_reply_bytes)
        # The core's CallPort, what the fronts are opened on (daemon/core/inbox.py); a polled
        # front (galton-daemon --zmq) is read on this thread.
        self.intake = Intake(wiring.polled, self.status_board.answer, self.client_gone)
        self._event_seq = 0
        self._stopping = False
        self.refresh_clock()
        self.tune_switch_interval()

    # -- what the wiring gave (read-only: handlers see these through core/context.py) ----
    @property
    def instance(self) -> str:
        return self.wiring.instance

    @property
    def limits(self) -> Limits:
        return self.wiring.limits

    @property
    def engine_factory(self) -> Callable[[str], Any] | None:
        return self.wiring.engine_factory

    @property
    def snapshot_key(self) -> bytes | None:
        return self.wiring.snapshot_key

    @property
    def client_alive(self) -> Callable[[str], bool | None] | None:
        return self.wiring.client_alive

    @property
    def advertised(self) -> dict[str, Any]:
        """What capabilities adds from the fronts (ZeroMQ's endpoints)."""
        return self.wiring.advertised()

    def tune_switch_interval(self) -> None:
        """Set the process's switch interval for this world's engine (see above)."""
        holds_gil = not self.world.engine.releases_gil_while_stepping
        sys.setswitchinterval(SHORT_SWITCH_INTERVAL_S if holds_gil else DEFAULT_SWITCH_INTERVAL_S)

    # -- the physics thread -------------------------------------------------------------
    def stop(self) -> None:
        """Any thread: end ``run`` once what it is doing is done."""
        self._stopping = True
        self.intake.put(None)

    def run(self) -> None:
        """The physics thread's body; returns after ``stop()``, every query answered.

        Nothing a request does can end it: whatever escapes a tick is logged, the world is
        paused (faulted if it diverged), and the loop goes on serving."""
        while not self._stopping:
            try:
                self._tick()
            except Exception as exc:
                self._recover(exc)
        self._answer_leftovers()

    def _tick(self) -> None:
        """Physics first (the steps due now), then telemetry, then requests until the next
        step is due."""
        self.stepping.advance()
        self._start_queued()
        now = time.monotonic()
        if self.status_board.telemetry_due(now):
            self.publish_telemetry(now)
        if now >= self.streams.next_due:
            self.streams.publish_due(self, now)
        checkpoints = self.wiring.checkpoints
        if checkpoints is not None and now >= self._next_checkpoint:
            self._next_checkpoint = now + checkpoints.period_s
            checkpoints.save()
        self._take_calls(self._idle_timeout())

    def publish_telemetry(self, now: float) -> None:
        """One telemetry sample per world, after checking the live world is still finite
        and measuring its real-time factor."""
        if not self.world.faulted:
            self.stepping.verify()
        self.rtf = self.rtf_window.add(now, self.world.sim_time)
        self.status_board.publish_telemetry()

    def _start_queued(self) -> None:
        """With no step job running, handle the waiting step requests in arrival order
        until one starts a job (daemon/core/step_queue.py)."""
        while self.job is None and (call := self.step_queue.head()) is not None:
            self.handle(call)
            self.step_queue.done(call)

    def _recover(self, exc: Exception) -> None:
        """The last line of defence: an error no request handler caught pauses the world."""
        if isinstance(exc, PhysicsError):
            self.stepping.fault(exc)
            return
        log.exception("the physics loop caught an unexpected error; the world is paused")
        error = OperationFailedError(f"the engine failed: {type(exc).__name__}: "
                                     f"{brief(str(exc))}")
        job = self.end_job()
        if job is not None:
            self.replies.error(job.call, error)
        self.set_state(SimState.PAUSED)
        self.emit({"kind": "error", "message": error.message})

    def _idle_timeout(self) -> float:
        now = time.monotonic()
        next_due = min(self.status_board.next_telemetry, self.streams.next_due)
        until_telemetry = max(0.0, next_due - now)
        if self.job is not None:
            return 0.0
        if self.state == SimState.PLAYING:
            due = self.pacer.seconds_until_due(now, self.world.sim_time, self.world.engine.timestep)
            return min(due, until_telemetry)
        return until_telemetry

    def _take_calls(self, timeout: float) -> None:
        """Answer requests until the next step is due, waiting up to ``timeout`` s for the
        first (for ever when infinite: nothing due). With steps due now, requests get
        REQUEST_SLICE_S, and at least one is answered."""
        started = time.monotonic()
        deadline = started + max(timeout, REQUEST_SLICE_S)
        inbox = self.intake.inbox
        try:
            if timeout <= 0:
                item = inbox.get_nowait()
            else:
                item = inbox.get(timeout=None if math.isinf(timeout) else timeout)
        except queue.Empty:
            return
        while item is not None:
            self._take(item)
            now = time.monotonic()
            # A step job a request started is due now: back to the physics after the slice
            # (else a crowd of step(1) callers is refused until the next telemetry).
            if now >= deadline or (self.job is not None and now >= started + REQUEST_SLICE_S):
                return
            try:
                item = inbox.get_nowait()
            except queue.Empty:
                return

    def _take(self, item: Call | Task) -> None:
        if isinstance(item, Task):
            try:
                item.run()
            finally:
                self.stepping.keep_invariants()
        else:
            self.handle(item)

    def _answer_leftovers(self) -> None:
        closing = OperationFailedError("the daemon is shutting down")
        job = self.end_job()
        if job is not None:
            self.replies.error(job.call, closing)
        while (waiting := self.step_queue.take()) is not None:
            self.replies.error(waiting, closing)
        for call in self.intake.leftovers():
            self.replies.error(call, closing)

    # -- requests -----------------------------------------------------------------------
    def handle(self, call: Call) -> None:
        """Answer one call (or start its step job); never raises. A rejected request has
        changed nothing: every check runs before anything is applied."""
        try:
            request = decode_request(call.payload, call.op or None, self.decode_limits)
            call.op = request.op
            op = operation(request.op)
            refuse_by_role(call.role, op.name)
            typed = op.decode(request.args)  # the declared request, or INVALID_ARGUMENT
            self.world_for(typed)  # an unknown world is refused before anything
            call.client = request.client
            call.world = typed.world if isinstance(typed.world, str) else None
            lease.check(self, call, op)  # while another client holds control: refused
            with self.wiring.work_guard() if op.mutates and not op.steps else nullcontext():
                result = HANDLERS[op.name](self, call, typed)
            self.stepping.keep_invariants()  # before the reply: what the client asks next sees it
            if result is not None:
                self.replies.ok(call, result)
        except StepBusyError:  # another step request runs: this one waits for it
            self._hold_step(call)
        except RemoteError as error:
            self.stepping.keep_invariants()
            self.replies.error(call, error)
        except Exception as exc:  # the daemon keeps serving whatever an engine does
            log.exception("operation %s failed", call.op)
            self.stepping.keep_invariants()
            self.replies.error(call, OperationFailedError(
                f"{type(exc).__name__}: {brief(str(exc))}"))

    def _hold_step(self, call: Call) -> None:
        try:
            self.step_queue.hold(call)
        except RemoteError as error:
            self.replies.error(call, error)

    def set_state(self, state: SimState) -> None:
        """Move the state machine, announcing a change with a ``state`` event."""
        if state == SimState.PLAYING:
            self.pacer.anchor(time.monotonic(), self.world.sim_time, self.target_rtf)
        if state != self.state:
            self.state = state
            self.emit({"kind": "state", "state": state.value, "step": self.world.step_index,
                       "sim_time": self.world.sim_time})

    def client_gone(self, client: str) -> None:
        """A client's liveliness token vanished (called from a Task on this thread)."""
        time_control.client_gone(self, client)
        self.streams.owner_gone(client)

    def check_job_reads(self) -> None:
        """A step job whose read entities are gone is answered now, not after its steps."""
        job_results.answer_if_reads_gone(self)

    def emit(self, event: dict[str, Any]) -> None:
        """Publish an event with the next sequence number: a gap tells a subscriber what it
        missed."""
        self._event_seq += 1
        try:
            self.wiring.publish(EVENTS, msgpack.packb(
                {"instance": self.instance, "seq": self._event_seq, **event}))
        except Exception:
            log.exception("could not publish an event")

    def world_for(self, args: dict[str, Any] | Args) -> World:
        """The world a request is for: the one its ``world`` names, else the live one."""
        name = args.get("world") if isinstance(args, dict) else args.world
        if name is None or name == self.world.name:
            return self.world
        found = self.side.get(name) if isinstance(name, str) else None
        if found is None:
            known = [self.world.name, *self.side]
            raise NotFoundError(f"no world named {brief(name)}"
                                f"{did_you_mean(str(name)[:64], known)}; worlds: "
                                f"{', '.join(known)}")
        return found

    # -- the step job (its steps: daemon/core/stepping.py) ----------------------------
    def start_job(self, job: StepJob) -> None:
        """Make ``job`` the step job: the one place it is set (``OpContext``)."""
        self.job = job

    def end_job(self) -> StepJob | None:
        """End the step job, if any, and return it for its caller to answer: the one place
        it is cleared."""
        job, self.job = self.job, None
        return job

    def finish_job(self, job: StepJob) -> None:
        """Answer a finished step request: {steps}, and the states it asked to read (after
        the last step, verified), and with until_rest whether they rest (a prediction: its
        samples). A body deleted meanwhile fails the read, not the steps."""
        try:
            result = job_results.job_result(job.world or self.world, job)
        except RemoteError as error:
            error.details["steps_done"] = job.done
            self.replies.error(job.call, error)
            return
        finally:
            job.release()
        self.replies.ok(job.call, result)

    # -- status (daemon/core/loop_status.py) ------------------------------------------
    def refresh_clock(self) -> None:
        """Publish the world's clock to other threads as one value, swapped atomically."""
        self.status_board.refresh()

    def status(self) -> SimStatus:
        """Safe to call from any thread: reads only values swapped atomically."""
        return self.status_board.status()
