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
from typing import Any

import numpy as np

from galton.daemon.calls import Call, StepJob
from galton.daemon.loop_state import StateOps
from galton.daemon.monitor import Pacer, ProcessMonitor, RtfWindow
from galton.daemon.ops import MUTATING_OPS, SCENE_OPS
from galton.daemon.world import World
from galton.protocol import (
    NotFoundError,
    OperationFailedError,
    PhysicsError,
    RemoteError,
    Reply,
    ResultCode,
    SimStatus,
    Telemetry,
    UnknownOperationError,
    decode_request,
    encode_reply,
    error_reply,
    pack_f64,
)
from galton.protocol.errors import did_you_mean

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


class SimLoop(StateOps):
    """Owns the World and the simulation state machine (stopped / playing / paused)."""

    def __init__(self, world: World, instance: str,
                 publish_telemetry: Callable[[Telemetry], None],
                 publish_event: Callable[[dict[str, Any]], None],
                 telemetry_rate_hz: float = 10.0,
                 engine_factory: Callable[[str], Any] | None = None) -> None:
        self.world = world
        self.instance = instance
        self.inbox: queue.SimpleQueue[Call | None] = queue.SimpleQueue()
        self.state = "stopped"
        self.target_rtf = 1.0
        self.job: StepJob | None = None
        self.pacer = Pacer()
        self.rtf_window = RtfWindow()
        self.monitor = ProcessMonitor()
        self.publish_telemetry = publish_telemetry
        self.publish_event = publish_event
        self.telemetry_period = 1.0 / telemetry_rate_hz if telemetry_rate_hz > 0 else math.inf
        self.engine_factory = engine_factory
        self._step_cost = 1e-4
        self._last_verify = 0.0
        self._seq = 0
        self._stopping = False
        self.rtf = 0.0
        self._status_reply: tuple[bytes, tuple[Any, ...], bytes] | None = None
        self.clock: tuple[int, float, float, int, bool] = (0, 0.0, 0.0, 0, False)
        self.refresh_clock()
        self.tune_switch_interval()

    def tune_switch_interval(self) -> None:
        """Set the process's switch interval for this world's engine (see above)."""
        holds_gil = not self.world.engine.releases_gil_while_stepping
        sys.setswitchinterval(SHORT_SWITCH_INTERVAL_S if holds_gil else DEFAULT_SWITCH_INTERVAL_S)

    # -- threads ------------------------------------------------------------------------
    def submit(self, call: Call) -> None:
        """Called from Zenoh's threads: hand a request to the physics thread."""
        self.inbox.put(call)

    def stop(self) -> None:
        self._stopping = True
        self.inbox.put(None)

    def run(self) -> None:
        """The physics thread's body; returns after ``stop()``, every query answered."""
        next_telemetry = time.monotonic()
        while not self._stopping:
            self._take_calls(self._idle_timeout(next_telemetry))
            if self._stopping:
                break
            self._advance()
            now = time.monotonic()
            if now >= next_telemetry:
                self._publish_telemetry(now)
                next_telemetry = max(next_telemetry + self.telemetry_period, now)
        self._answer_leftovers()

    def _idle_timeout(self, next_telemetry: float) -> float:
        now = time.monotonic()
        until_telemetry = max(0.0, next_telemetry - now)
        if self.job is not None:
            return 0.0
        if self.state == "playing":
            due = self.pacer.seconds_until_due(now, self.world.sim_time, self.world.engine.timestep)
            return min(due, until_telemetry)
        return until_telemetry

    def _take_calls(self, timeout: float) -> None:
        """Answer what is in the inbox, waiting up to ``timeout`` s for the first call
        (for ever when infinite: nothing due, e.g. paused with telemetry off)."""
        try:
            if timeout <= 0:
                call = self.inbox.get_nowait()
            else:
                call = self.inbox.get(timeout=None if math.isinf(timeout) else timeout)
        except queue.Empty:
            return
        while call is not None:
            self.handle(call)
            try:
                call = self.inbox.get_nowait()
            except queue.Empty:
                return

    def _answer_leftovers(self) -> None:
        closing = OperationFailedError("the daemon is shutting down")
        if self.job is not None:
            self._reply_error(self.job.call, closing)
            self.job = None
        while True:
            try:
                call = self.inbox.get_nowait()
            except queue.Empty:
                return
            if call is not None:
                self._reply_error(call, closing)

    # -- requests -----------------------------------------------------------------------
    def handle(self, call: Call) -> None:
        """Answer one call (or start its step job); never raises."""
        try:
            request = decode_request(call.payload, call.op)
            self._require_world(request.args)
            state_op = self.STATE_OPS.get(request.op)
            if state_op is not None:
                result = state_op(self, call, request.args)
                if result is not None:
                    self._reply_ok(call, result)
                return
            scene_op = SCENE_OPS.get(request.op)
            if scene_op is None:
                known = sorted([*SCENE_OPS, *self.STATE_OPS])
                raise UnknownOperationError(
                    f"unknown operation {request.op!r}{did_you_mean(request.op, known)}",
                    {"operations": known})
            result = scene_op(self.world, request.args)
            if request.op in MUTATING_OPS:
                self.publish_event({"kind": "scene", "op": request.op,
                                    "step": self.world.step_index})
            self._reply_ok(call, result)
        except RemoteError as error:
            self._reply_error(call, error)
        except Exception as exc:  # the daemon keeps serving whatever an engine does
            log.exception("operation %s failed", call.op)
            self._reply_error(call, OperationFailedError(f"{type(exc).__name__}: {exc}"))

    def _require_world(self, args: dict[str, Any]) -> None:
        """Requests may name a world; this daemon serves one (room for several later)."""
        world = args.get("world", self.world.name)
        if world != self.world.name:
            raise NotFoundError(f"no world named {world!r}: this daemon serves one world, "
                                f"{self.world.name!r}")

    def _reply_ok(self, call: Call, result: dict[str, Any]) -> None:
        self.refresh_clock()
        reply = Reply(ResultCode.OK, result=result, step=self.world.step_index,
                      sim_time=self.world.sim_time)
        self._send(call, encode_reply(reply))

    def _reply_error(self, call: Call, error: RemoteError) -> None:
        self.refresh_clock()
        reply = error_reply(error, self.world.step_index, self.world.sim_time)
        self._send(call, encode_reply(reply))

    def _send(self, call: Call, data: bytes) -> None:
        try:
            call.respond(data)
        except Exception:
            log.exception("could not answer a %s request", call.op)

    # -- physics ------------------------------------------------------------------------
    def _advance(self) -> None:
        """Run one chunk of steps: a pending step job's, or the paced playing clock's."""
        if self.job is not None:
            self._run_steps(min(self.job.steps_to_next_check(), self._chunk_size()))
        elif self.state == "playing":
            due = self.pacer.steps_due(time.monotonic(), self.world.sim_time,
                                       self.world.engine.timestep)
            count = self._chunk_size() if due < 0 else min(due, self._chunk_size())
            if count:
                self._run_steps(count)

    def _chunk_size(self) -> int:
        return max(1, min(10_000, int(CHUNK_WALL_S / self._step_cost)))

    def _run_steps(self, count: int) -> None:
        started = time.perf_counter()
        self.world.step(count)
        now = time.perf_counter()
        self._step_cost = 0.8 * self._step_cost + 0.2 * max((now - started) / count, 1e-7)
        job = self.job
        job_done = job is not None and job.remaining == count
        checking = job is not None and job.rest is not None and (
            (job.done + count) % job.rest.every == 0)
        due = job_done or checking or now - self._last_verify >= VERIFY_PERIOD_S
        if due and not self.verify_physics():
            return
        self.refresh_clock()
        if job is not None:
            job.remaining -= count
            if job_done or (checking and self._at_rest(job)):
                self.job = None
                self._finish_job(job)

    def _at_rest(self, job: StepJob) -> bool:
        """Whether every body the job reads moves slower than its rest speed."""
        try:
            _, twists = self.world.get_states(job.read or [])
        except RemoteError:
            return True  # one was deleted: finish now, the reply says which
        return _resting(twists, job)

    def _finish_job(self, job: StepJob) -> None:
        """Answer a finished step request: {steps}, and the states it asked to read (after
        the last step, verified), and with until_rest whether they rest. A body deleted
        meanwhile fails the read, not the steps."""
        result: dict[str, Any] = {"steps": job.done}
        if job.read is not None:
            try:
                poses, twists = self.world.get_states(job.read)
            except RemoteError as error:
                error.details["steps_done"] = job.done
                self._reply_error(job.call, error)
                return
            result.update(names=job.read, poses=pack_f64(poses), twists=pack_f64(twists))
            if job.rest is not None:
                result["at_rest"] = _resting(twists, job)
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
        self._set_state("paused")
        self.publish_event({"kind": "physics_error", "message": error.message,
                            "step": self.world.step_index, "sim_time": self.world.sim_time})
        if self.job is not None:
            job, self.job = self.job, None
            self._reply_error(job.call, error)

    # -- status & telemetry -------------------------------------------------------------
    def refresh_clock(self) -> None:
        """Publish the world's clock to other threads as one tuple, swapped atomically."""
        world = self.world
        self.clock = (world.step_index, world.sim_time, world.engine.timestep,
                      len(world.entities), world.faulted)

    def status(self) -> SimStatus:
        """Safe to call from any thread: reads only values swapped atomically."""
        return self._status_from(self._status_snapshot())

    def _status_snapshot(self) -> tuple[Any, ...]:
        """Everything a status reply says, read once: equal snapshots give equal replies."""
        return (self.clock, self.state, self.target_rtf, self.rtf, self.world)

    def _status_from(self, snapshot: tuple[Any, ...]) -> SimStatus:
        (step, sim_time, timestep, count, faulted), state, target_rtf, rtf, world = snapshot
        return SimStatus(
            state=state, step=step, sim_time=sim_time, timestep=timestep,
            target_rtf=target_rtf, rtf=rtf, entity_count=count, engine=world.engine.name,
            instance=self.instance, world=world.name, faulted=faulted)

    def handle_readonly(self, call: Call) -> None:
        """Answer a status request on the caller's thread, from the atomic snapshot.

        A controller polling a paused or idle daemon asks the same thing of the same
        snapshot again and again, so the last reply's bytes are kept with the request and
        snapshot they answer: a repeated poll costs one comparison, not a decode and an
        encode (about 30 µs of a 0.3 ms round trip, docs/PERFORMANCE.md)."""
        snapshot = self._status_snapshot()
        cached = self._status_reply
        if cached is not None and cached[0] == call.payload and cached[1] == snapshot:
            self._send(call, cached[2])
            return
        status = self._status_from(snapshot)
        try:
            self._require_world(decode_request(call.payload, call.op).args)
            reply = Reply(ResultCode.OK, result=status.to_wire(), step=status.step,
                          sim_time=status.sim_time)
        except RemoteError as error:
            self._send(call, encode_reply(error_reply(error, status.step, status.sim_time)))
            return
        data = encode_reply(reply)
        self._status_reply = (call.payload, snapshot, data)
        self._send(call, data)

    def _publish_telemetry(self, now: float) -> None:
        if not self.world.faulted:
            self.verify_physics()
        cpu, rss, peak = self.monitor.sample()
        rtf = self.rtf = self.rtf_window.add(now, self.world.sim_time)
        self._seq += 1
        world = self.world
        sample = Telemetry(
            seq=self._seq, instance=self.instance, engine=world.engine.name, state=self.state,
            step=world.step_index, sim_time=world.sim_time, wall_time=time.time(), rtf=rtf,
            target_rtf=self.target_rtf, timestep=world.engine.timestep,
            entity_count=len(world.entities), cpu_percent=cpu, rss_bytes=rss,
            peak_rss_bytes=peak, world=world.name)
        try:
            self.publish_telemetry(sample)
        except Exception:
            log.exception("could not publish telemetry")


def _resting(twists: np.ndarray, job: StepJob) -> bool:
    """Every body's linear speed under the job's rest speed."""
    assert job.rest is not None
    return bool((np.linalg.norm(twists[:, :3], axis=1) < job.rest.speed).all())
