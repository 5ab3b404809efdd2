"""The physics thread: applies requests between steps, paces the clock, publishes telemetry.

Everything that touches the engine runs here, on one thread (galton-daemon's main thread;
``Daemon.start`` gives it a thread of its own when embedded). Zenoh callbacks only put
``Call`` objects into the inbox; this loop answers each of them exactly once.
"""

from __future__ import annotations

import logging
import math
import queue
import sys
import time
from collections.abc import Callable
from contextlib import AbstractContextManager, nullcontext
from typing import Any

from galton.daemon.access import lease
from galton.daemon.access.zmq_auth import refuse_by_role
from galton.daemon.core import job_results, loop_status, side_jobs, time_control
from galton.daemon.core.calls import (
    Call,
    Inbox,
    PolledSource,
    StepJob,
    Task,
    smoothed_step_cost,
)
from galton.daemon.core.inbox import PolledInbox
from galton.daemon.core.limits import DEFAULT_LIMITS, Limits
from galton.daemon.core.monitor import Pacer, ProcessMonitor, RtfWindow
from galton.daemon.core.reply_limit import too_big
from galton.daemon.core.step_queue import StepBusyError, StepQueue
from galton.daemon.ops.handlers import HANDLERS
from galton.daemon.world.scene import World
from galton.daemon.world.slots import SnapshotSlots
from galton.daemon.world.state_streams import StateStreams
from galton.protocol import (
    DecodeLimits,
    NotFoundError,
    OperationFailedError,
    PhysicsError,
    RemoteError,
    Reply,
    ResultCode,
    SimState,
    SimStatus,
    Telemetry,
    decode_request,
    encode_reply,
    error_reply,
)
from galton.protocol.errors import brief, did_you_mean
from galton.protocol.operations import OPERATIONS, operation
from galton.protocol.requests import Args

log = logging.getLogger("galton.daemon")

CHUNK_WALL_S = 0.005  # physics work between two looks at the inbox
# Python's switch interval while the engine holds the GIL as it steps (PyBullet): short, so
# status requests on Zenoh's threads get in between steps. A waiting thread asks for the GIL
# only after this long and then waits for the step to end: under load, status p50 is 9 ms
# at the default 5 ms, 1.4 ms at 0.5 ms and 0.84 ms at 0.05 ms, with no measurable cost to
# the trial. An engine that releases the GIL (MuJoCo) keeps the default, which runs its
# trials 2-3 % faster (docs/PERFORMANCE.md).
SHORT_SWITCH_INTERVAL_S = 0.00005
DEFAULT_SWITCH_INTERVAL_S = 0.005
VERIFY_PERIOD_S = 0.05  # the state is checked finite at least this often while stepping
# Physics before requests: while steps are due now (a step job, RTF 0, a world behind its
# clock), requests get at most this much of the physics thread between two chunks of steps
# (a chunk is CHUNK_WALL_S), and always at least one request, so neither side starves.
REQUEST_SLICE_S = 0.001
# A playing world behind its clock runs chunks of due steps back to back for up to this
# long before the next request (see SimLoop._play_due).
CATCH_UP_S = 0.05


class SimLoop:
    """Owns the World and the simulation state machine (stopped / playing / paused)."""

    def __init__(self, world: World, instance: str,
                 publish_telemetry: Callable[[Telemetry], None],
                 publish_event: Callable[[dict[str, Any]], None],
                 telemetry_rate_hz: float = 10.0,
                 engine_factory: Callable[[str], Any] | None = None,
                 limits: Limits = DEFAULT_LIMITS,
                 polled: PolledSource | None = None) -> None:
        self.world = world
        self.instance = instance
        self.limits = limits
        self.decode_limits = DecodeLimits(
            max_bytes=limits.max_request_bytes, max_depth=limits.max_depth,
            max_string=limits.max_string_bytes,
            long_text_keys=frozenset(a.name for op in OPERATIONS.values() for a in op.args
                                     if a.long_text))
        # A polled front (galton-daemon --zmq) is read on this thread: the core's PolledInbox.
        self.inbox: Inbox = (PolledInbox(polled, self._gone_task) if polled is not None
                             else queue.SimpleQueue())
        self.advertised: dict[str, Any] = {}  # what capabilities adds (ZeroMQ endpoints)
        # Whether a client is there, as the fronts know it (server.py: Fronts.client_alive;
        # None when embedded): the lease and the state streams are tied to it.
        self.client_alive: Callable[[str], bool | None] | None = None
        self.state = SimState.STOPPED
        self.target_rtf = 1.0
        self.job: StepJob | None = None
        self.step_queue = StepQueue()  # step requests waiting for the job (step_queue.py)
        self.lease = lease.Lease()  # who holds control (daemon/access/lease.py)
        self.pacer = Pacer()
        self.rtf_window = RtfWindow()
        self.monitor = ProcessMonitor()
        self.publish_telemetry = publish_telemetry
        self.publish_event = publish_event
        self.streams = StateStreams()  # stream_states (daemon/world/state_streams.py)
        self.telemetry_period = 1.0 / telemetry_rate_hz if telemetry_rate_hz > 0 else math.inf
        self.engine_factory = engine_factory
        self.side: dict[str, World] = {}  # side worlds by name (daemon/ops/worlds.py)
        # galton-daemon --state-dir: saves the live world every checkpoint_period seconds.
        self.checkpoint: Callable[[], None] | None = None
        self.checkpoint_period = 10.0
        self._next_checkpoint = time.monotonic() + self.checkpoint_period
        self.slots = SnapshotSlots(limits)
        self.snapshot_key: bytes | None = None  # galton-daemon --snapshot-key: blobs' seal
        self._step_cost = 1e-4
        self._last_verify = 0.0
        self.telemetry_seq = 0
        self._event_seq = 0
        self._stopping = False
        self.rtf = 0.0
        # The last status reply with the request and snapshot it answered (loop_status.py).
        self.status_reply: tuple[bytes, tuple[Any, ...], bytes] | None = None
        # Wraps each scene-changing request (spawn, delete, load_model...): galton-daemon
        # makes SIGTERM end the process at once inside it (server.sigterm_ends_at_once).
        self.work_guard: Callable[[], AbstractContextManager[None]] = nullcontext
        self.clock: tuple[int, float, float, int, bool] = (0, 0.0, 0.0, 0, False)
        self.refresh_clock()
        self.tune_switch_interval()

    def schedule_checkpoints(self, save: Callable[[], None], period_s: float) -> None:
        """Call ``save`` every ``period_s`` seconds between chunks of steps."""
        self.checkpoint, self.checkpoint_period = save, period_s
        self._next_checkpoint = time.monotonic() + period_s

    def tune_switch_interval(self) -> None:
        """Set the process's switch interval for this world's engine (see above)."""
        holds_gil = not self.world.engine.releases_gil_while_stepping
        sys.setswitchinterval(SHORT_SWITCH_INTERVAL_S if holds_gil else DEFAULT_SWITCH_INTERVAL_S)

    # -- threads ------------------------------------------------------------------------
    def submit(self, call: Call | Task) -> None:
        """Called from Zenoh's threads: hand a request (or a task) to the physics thread."""
        self.inbox.put(call)

    def dispatch(self, call: Call) -> None:
        """The core's call interface (``CallPort``): hand a request to the physics thread,
        or answer a fast one on the caller's thread -- the one path of every front."""
        declared = OPERATIONS.get(call.op)
        if declared is not None and declared.fast:
            self.handle_readonly(call)
        else:
            self.submit(call)

    def lose_client(self, client: str) -> None:
        """The core's call interface: a client has gone; its step job and lease end on the
        physics thread."""
        self.submit(Task(lambda: self.client_gone(client)))

    def _gone_task(self, client: str) -> Task:
        return Task(lambda: self.client_gone(client))

    def stop(self) -> None:
        self._stopping = True
        self.inbox.put(None)

    def run(self) -> None:
        """The physics thread's body; returns after ``stop()``, every query answered.

        Nothing a request does can end it: whatever escapes a tick is logged, the world is
        paused (faulted if it diverged), and the loop goes on serving."""
        next_telemetry = time.monotonic()
        while not self._stopping:
            try:
                next_telemetry = self._tick(next_telemetry)
            except Exception as exc:
                self._recover(exc)
        self._answer_leftovers()

    def _tick(self, next_telemetry: float) -> float:
        """Physics first (the steps due now), then telemetry, then requests until the next
        step is due; returns when the next telemetry sample is due."""
        self._advance()
        self._start_queued()
        now = time.monotonic()
        if now >= next_telemetry:
            loop_status.publish_telemetry(self, now)
            next_telemetry = max(next_telemetry + self.telemetry_period, now)
        if now >= self.streams.next_due:
            self.streams.publish_due(self, now)
        if self.checkpoint is not None and now >= self._next_checkpoint:
            self._next_checkpoint = now + self.checkpoint_period
            self.checkpoint()
        self._take_calls(self._idle_timeout(next_telemetry))
        return next_telemetry

    def _start_queued(self) -> None:
        """With no step job running, handle the waiting step requests in arrival order
        until one starts a job (daemon/core/step_queue.py)."""
        while self.job is None and (call := self.step_queue.head()) is not None:
            self.handle(call)
            self.step_queue.done(call)

    def _recover(self, exc: Exception) -> None:
        """The last line of defence: an error no request handler caught pauses the world."""
        if isinstance(exc, PhysicsError):
            self._fault(exc)
            return
        log.exception("the physics loop caught an unexpected error; the world is paused")
        error = OperationFailedError(f"the engine failed: {type(exc).__name__}: "
                                     f"{brief(str(exc))}")
        job = self.end_job()
        if job is not None:
            self.reply_error(job.call, error)
        self.set_state(SimState.PAUSED)
        self.emit({"kind": "error", "message": error.message})

    def _idle_timeout(self, next_telemetry: float) -> float:
        now = time.monotonic()
        until_telemetry = max(0.0, min(next_telemetry, self.streams.next_due) - now)
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
        try:
            if timeout <= 0:
                item = self.inbox.get_nowait()
            else:
                item = self.inbox.get(timeout=None if math.isinf(timeout) else timeout)
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
                item = self.inbox.get_nowait()
            except queue.Empty:
                return

    def _take(self, item: Call | Task) -> None:
        if isinstance(item, Task):
            try:
                item.run()
            finally:
                self._keep_invariants()
        else:
            self.handle(item)

    def _answer_leftovers(self) -> None:
        closing = OperationFailedError("the daemon is shutting down")
        job = self.end_job()
        if job is not None:
            self.reply_error(job.call, closing)
        while (waiting := self.step_queue.take()) is not None:
            self.reply_error(waiting, closing)
        while True:
            try:
                call = self.inbox.get_nowait()
            except queue.Empty:
                return
            if isinstance(call, Call):
                self.reply_error(call, closing)

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
            with self.work_guard() if op.mutates and not op.steps else nullcontext():
                result = HANDLERS[op.name](self, call, typed)
            self._keep_invariants()  # before the reply: what the client asks next sees it
            if result is not None:
                self._reply_ok(call, result)
        except StepBusyError:  # another step request runs: this one waits for it
            self._hold_step(call)
        except RemoteError as error:
            self._keep_invariants()
            self.reply_error(call, error)
        except Exception as exc:  # the daemon keeps serving whatever an engine does
            log.exception("operation %s failed", call.op)
            self._keep_invariants()
            self.reply_error(call, OperationFailedError(
                f"{type(exc).__name__}: {brief(str(exc))}"))

    def _hold_step(self, call: Call) -> None:
        try:
            self.step_queue.hold(call)
        except RemoteError as error:
            self.reply_error(call, error)

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

    def _keep_invariants(self) -> None:
        """A diverged world never plays or steps, whoever noticed the divergence."""
        live_job = self.job is not None and self.job.world is None
        if self.world.faulted and (self.state == SimState.PLAYING or live_job):
            self._fault(PhysicsError(
                f"the simulation diverged at step {self.world.step_index}; reset it (scope "
                "'state' or 'all') before playing or stepping"))

    def emit(self, event: dict[str, Any]) -> None:
        """Publish an event with the next sequence number: a gap tells a subscriber what it
        missed."""
        self._event_seq += 1
        try:
            self.publish_event({"seq": self._event_seq, **event})
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

    def _reply_ok(self, call: Call, result: dict[str, Any]) -> None:
        self.refresh_clock()
        world = self._stamping(call)
        reply = Reply(ResultCode.OK, result=result, step=world.step_index,
                      sim_time=world.sim_time)
        data = encode_reply(reply)
        if len(data) > self.limits.max_reply_bytes:  # never sent (daemon/core/reply_limit.py)
            self.reply_error(call, too_big(f"the reply to {call.op or 'this request'}",
                                           len(data), self.limits.max_reply_bytes,
                                           "ask for less"))
            return
        self.send(call, data)

    def reply_error(self, call: Call, error: RemoteError) -> None:
        self.refresh_clock()
        world = self._stamping(call)
        reply = error_reply(error, world.step_index, world.sim_time)
        self.send(call, encode_reply(reply))

    def _stamping(self, call: Call) -> World:
        """The world whose step and sim time a reply carries: the one the request named
        (the live one when it named none, or when that world is gone)."""
        if call.world is None:
            return self.world
        return self.side.get(call.world, self.world)

    def send(self, call: Call, data: bytes) -> None:
        try:
            call.respond(data)
        except Exception:
            log.exception("could not answer a %s request", call.op)

    # -- physics ------------------------------------------------------------------------
    def _advance(self) -> None:
        """Run one chunk of steps: a live step job's, or the paced playing clock's and then
        a side world's (or a prediction's) job, which never delays the live world."""
        job = self.job
        if job is not None and job.world is None:
            self._run_steps(min(job.steps_to_next_check(), self._chunk_size()))
            return
        if self.state == SimState.PLAYING:
            self._play_due()
        if job is not None and self.job is job:
            side_jobs.run_chunk(self, job)

    def _play_due(self) -> None:
        """The steps the playing clock owes now, chunk after chunk until it has caught up
        (for at most CATCH_UP_S): a request that held the thread for 20 ms (a render) is
        followed by all the steps it delayed, not by one chunk, or a steady load of such
        requests would slow the clock (issue 35, item 9). At RTF 0, one chunk. A state
        sample that falls due ends the catch-up too: a world whose step is slow would
        otherwise stream at the rate of its catch-ups (DART's 1,000 bodies: 12 a second
        of 60 asked), and the sample costs the same wherever it is taken."""
        started = time.monotonic()
        dt = self.world.engine.timestep
        while self.state == SimState.PLAYING:
            now = time.monotonic()
            due = self.pacer.steps_due(now, self.world.sim_time, dt)
            count = self._chunk_size() if due < 0 else min(due, self._chunk_size())
            if count:
                self._run_steps(count)
            if (due < 0 or count == due or now - started >= CATCH_UP_S
                    or time.monotonic() >= self.streams.next_due):
                return

    def _chunk_size(self) -> int:
        return max(1, min(10_000, int(CHUNK_WALL_S / self._step_cost)))

    def _run_steps(self, count: int) -> None:
        """Take ``count`` steps of the live world; they count towards a live step job only
        (a side world's job runs its own steps, daemon/core/side_jobs.py)."""
        started = time.perf_counter()
        self.world.step(count)
        now = time.perf_counter()
        self._step_cost = smoothed_step_cost(self._step_cost, now - started, count)
        job = self.job if self.job is not None and self.job.world is None else None
        job_done = job is not None and job.remaining == count
        checking = job is not None and job.rest is not None and (
            (job.done + count) % job.rest.every == 0)
        due = job_done or checking or now - self._last_verify >= VERIFY_PERIOD_S
        if due and not self.verify_physics():
            return
        self.refresh_clock()
        if job is not None:
            job.remaining -= count
            if job_done or (checking and job_results.at_rest(self.world, job)):
                self.end_job()
                self.finish_job(job)

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
            self.reply_error(job.call, error)
            return
        finally:
            job.release()
        self._reply_ok(job.call, result)

    def verify_physics(self) -> bool:
        """Check the unchecked steps; on a divergence, fault and return False."""
        self._last_verify = time.perf_counter()
        try:
            self.world.verify()
        except PhysicsError as error:
            self._fault(error)
            return False
        return True

    def _fault(self, error: PhysicsError) -> None:
        """A diverged step: pause, tell subscribers, fail the step job; never publish it."""
        self.refresh_clock()
        self.set_state(SimState.PAUSED)
        self.emit({"kind": "physics_error", "message": error.message,
                   "step": self.world.step_index, "sim_time": self.world.sim_time})
        job = self.job
        if job is not None and job.world is None:
            self.end_job()
            self.reply_error(job.call, error)

    # -- status & telemetry -------------------------------------------------------------
    def refresh_clock(self) -> None:
        """Publish the world's clock to other threads as one tuple, swapped atomically."""
        world = self.world
        self.clock = (world.step_index, world.sim_time, world.engine.timestep,
                      len(world.entities), world.faulted)

    def status(self) -> SimStatus:
        """Safe to call from any thread: reads only values swapped atomically."""
        return loop_status.status_from(self, loop_status.snapshot(self))

    def handle_readonly(self, call: Call) -> None:
        """Answer a status request on the caller's thread (daemon/core/loop_status.py)."""
        loop_status.answer_status(self, call)

