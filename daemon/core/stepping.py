"""The physics half of the loop (daemon/core/loop.py): the live world's steps in chunks
sized to CHUNK_WALL_S between two looks at the inbox, the playing clock's catch-up, the
checks that the state stayed finite, and what a divergence does.

Everything here runs on the physics thread, between requests, never during one.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Protocol

from galton.daemon.core import job_results, side_jobs
from galton.daemon.core.calls import smoothed_step_cost
from galton.daemon.core.context import Events, JobEnd
from galton.protocol import PhysicsError, SimState

if TYPE_CHECKING:
    from galton.daemon.core.monitor import Pacer
    from galton.daemon.world.state_streams import StateStreams

CHUNK_WALL_S = 0.005  # physics work between two looks at the inbox
VERIFY_PERIOD_S = 0.05  # the state is checked finite at least this often while stepping
# A playing world behind its clock runs chunks of due steps back to back for up to this
# long before the next request (see Stepping.play_due).
CATCH_UP_S = 0.05


class SteppedLoop(JobEnd, Events, Protocol):
    """What stepping needs of the loop: the live world and its step job, the playing
    clock, when the next state sample is due, and the state machine."""

    state: SimState
    pacer: Pacer
    streams: StateStreams

    def set_state(self, state: SimState) -> None: ...

    def refresh_clock(self) -> None: ...


class Stepping:
    """Takes the live world's steps for ``loop`` and learns what a step costs."""

    def __init__(self, loop: SteppedLoop) -> None:
        self.loop = loop
        self.step_cost = 1e-4  # seconds per step of the live world, smoothed
        self._last_verify = 0.0

    def advance(self) -> None:
        """Run one chunk of steps: a live step job's, or the paced playing clock's and then
        a side world's (or a prediction's) job, which never delays the live world."""
        loop = self.loop
        job = loop.job
        if job is not None and job.world is None:
            self.run_steps(min(job.steps_to_next_check(), self.chunk_size()))
            return
        if loop.state == SimState.PLAYING:
            self.play_due()
        if job is not None and loop.job is job:
            side_jobs.run_chunk(loop, job)

    def play_due(self) -> None:
        """The steps the playing clock owes now, chunk after chunk until it has caught up
        (for at most CATCH_UP_S): a request that held the thread for 20 ms (a render) is
        followed by all the steps it delayed, not by one chunk, or a steady load of such
        requests would slow the clock (issue 35, item 9). At RTF 0, one chunk. A state
        sample that falls due ends the catch-up too: a world whose step is slow would
        otherwise stream at the rate of its catch-ups (DART's 1,000 bodies: 12 a second
        of 60 asked), and the sample costs the same wherever it is taken."""
        loop = self.loop
        started = time.monotonic()
        dt = loop.world.engine.timestep
        while loop.state == SimState.PLAYING:
            now = time.monotonic()
            due = loop.pacer.steps_due(now, loop.world.sim_time, dt)
            count = self.chunk_size() if due < 0 else min(due, self.chunk_size())
            if count:
                self.run_steps(count)
            if (due < 0 or count == due or now - started >= CATCH_UP_S
                    or time.monotonic() >= loop.streams.next_due):
                return

    def chunk_size(self) -> int:
        """Steps that take about CHUNK_WALL_S at the cost learnt so far."""
        return max(1, min(10_000, int(CHUNK_WALL_S / self.step_cost)))

    def run_steps(self, count: int) -> None:
        """Take ``count`` steps of the live world; they count towards a live step job only
        (a side world's job runs its own steps, daemon/core/side_jobs.py)."""
        loop = self.loop
        started = time.perf_counter()
        loop.world.step(count)
        now = time.perf_counter()
        self.step_cost = smoothed_step_cost(self.step_cost, now - started, count)
        job = loop.job if loop.job is not None and loop.job.world is None else None
        job_done = job is not None and job.remaining == count
        checking = job is not None and job.rest is not None and (
            (job.done + count) % job.rest.every == 0)
        due = job_done or checking or now - self._last_verify >= VERIFY_PERIOD_S
        if due and not self.verify():
            return
        loop.refresh_clock()
        if job is not None:
            job.remaining -= count
            if job_done or (checking and job_results.at_rest(loop.world, job)):
                loop.end_job()
                loop.finish_job(job)

    def verify(self) -> bool:
        """Check the unchecked steps; on a divergence, fault and return False."""
        self._last_verify = time.perf_counter()
        try:
            self.loop.world.verify()
        except PhysicsError as error:
            self.fault(error)
            return False
        return True

    def keep_invariants(self) -> None:
        """A diverged world never plays or steps, whoever noticed the divergence."""
        loop = self.loop
        live_job = loop.job is not None and loop.job.world is None
        if loop.world.faulted and (loop.state == SimState.PLAYING or live_job):
            self.fault(PhysicsError(
                f"the simulation diverged at step {loop.world.step_index}; reset it (scope "
                "'state' or 'all') before playing or stepping"))

    def fault(self, error: PhysicsError) -> None:
        """A diverged step: pause, tell subscribers, fail the step job; never publish it."""
        loop = self.loop
        loop.refresh_clock()
        loop.set_state(SimState.PAUSED)
        loop.emit({"kind": "physics_error", "message": error.message,
                   "step": loop.world.step_index, "sim_time": loop.world.sim_time})
        job = loop.job
        if job is not None and job.world is None:
            loop.end_job()
            loop.replies.error(job.call, error)
