"""Steps of a side world or of a prediction: run in chunks on the physics thread after the
live world's due steps, so they never delay it (each chunk is at most about CHUNK_WALL_S of
work, sized from the job's own measured step cost)."""

from __future__ import annotations

import logging
import time

from galton.daemon.core import job_results
from galton.daemon.core.calls import StepJob, smoothed_step_cost
from galton.daemon.core.context import JobEnd
from galton.protocol import OperationFailedError, PhysicsError, RemoteError
from galton.protocol.errors import brief

log = logging.getLogger("galton.daemon")

# Short chunks: a live control call waits at most about this long behind a prediction.
CHUNK_WALL_S = 0.002
# A prediction of several futures steps them all in one chunk (on the engine's threads
# where it has them): at 2 ms a chunk of 8 MuJoCo futures of a 100-ball world is one step,
# and its hand-offs cost a third of the work (docs/PERFORMANCE.md, "Imagination"). Its
# chunks are longer, so a control call may wait up to this long behind an ensemble.
FUTURES_CHUNK_WALL_S = 0.010


def chunk_wall(job: StepJob) -> float:
    """The work one chunk of ``job`` may hold the physics thread for."""
    several = job.futures is not None and len(job.futures) > 1
    return FUTURES_CHUNK_WALL_S if several else CHUNK_WALL_S


def run_chunk(ctx: JobEnd, job: StepJob) -> None:
    """One chunk of a side job's steps; answers it when done, at rest, or failed."""
    if job.driver is not None:
        run_driven(ctx, job)
        return
    world = job.world
    assert world is not None
    count = min(job.steps_to_next_check(), max(1, int(chunk_wall(job) / job.step_cost)))
    started = time.perf_counter()
    try:
        if job.futures is not None:
            job.futures.step(count)
        else:
            world.step(count)
        job.step_cost = smoothed_step_cost(job.step_cost, time.perf_counter() - started,
                                           count)
        job.remaining -= count
        finished = job.remaining == 0
        if job.sampler is not None and job.done % job.sampler.every == 0:
            job.sampler.take(world)
        checking = job.rest is not None and job.done % job.rest.every == 0
        resting = checking and job_results.at_rest(world, job)
        if finished or resting:
            (job.futures or world).verify()
    except RemoteError as error:  # a diverged side world fails its job, not the daemon
        end(ctx, job, error)
        return
    except Exception as exc:  # nor does its engine failing pause the live world
        log.exception("a side world's steps failed")
        end(ctx, job, OperationFailedError(f"the engine failed: {type(exc).__name__}: "
                                            f"{brief(str(exc))}"))
        return
    if finished or resting:
        ctx.end_job()
        ctx.finish_job(job)


def run_driven(ctx: JobEnd, job: StepJob) -> None:
    """One chunk of a driven side job (calibrate's: one prediction); answers it when its
    driver has finished, or failed."""
    assert job.driver is not None
    try:
        job.remaining = max(0, job.remaining - job.driver.advance())
        finished = job.driver.finished
    except RemoteError as error:
        end(ctx, job, error)
        return
    except Exception as exc:
        log.exception("a driven side job failed")
        end(ctx, job, OperationFailedError(f"the engine failed: {type(exc).__name__}: "
                                            f"{brief(str(exc))}"))
        return
    if finished:
        ctx.end_job()
        ctx.finish_job(job)


def end(ctx: JobEnd, job: StepJob, error: RemoteError) -> None:
    """Answer a side job with an error and release what it held."""
    if ctx.job is job:
        ctx.end_job()
    if isinstance(error, PhysicsError):
        error.details["steps_done"] = job.done
    job.release()
    ctx.replies.error(job.call, error)
