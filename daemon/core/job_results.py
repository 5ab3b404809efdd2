"""What a finished step request answers, and when a resting one may stop early: the same
for the live world's jobs and for side worlds' and predictions' (daemon/core/side_jobs.py)."""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.core.calls import StepJob
from galton.daemon.core.context import JobEnd
from galton.daemon.ops.joints import joint_states
from galton.daemon.world.world import World
from galton.protocol import NotFoundError, RemoteError, pack_f64
from galton.protocol.errors import brief


def resting(twists: np.ndarray, job: StepJob) -> bool:
    """Every body's linear speed under the job's rest speed."""
    assert job.rest is not None
    return bool((np.linalg.norm(twists[:, :3], axis=1) < job.rest.speed).all())


def at_rest(world: World, job: StepJob) -> bool:
    """Whether every body the job reads moves slower than its rest speed (a body deleted
    meanwhile ends the job now: its reply says which)."""
    try:
        _, twists = world.get_states(job.read or [])
    except RemoteError:
        return True
    return resting(twists, job)


def job_result(world: World, job: StepJob) -> dict[str, Any]:
    """{steps}, the states it asked to read (after the last step, verified), and with
    until_rest whether they rest; a prediction: its samples."""
    if job.driver is not None:
        return job.driver.result()
    if job.sampler is not None:
        return job.sampler.result(job.done)
    result: dict[str, Any] = {"steps": job.done}
    if job.read is not None:
        poses, twists = world.get_states(job.read)
        result.update(names=job.read, poses=pack_f64(poses), twists=pack_f64(twists))
        if job.rest is not None:
            result["at_rest"] = resting(twists, job)
    if job.read_joints is not None:
        result["joints"] = joint_states(world, job.read_joints, "read_joints")
    return result


def answer_if_reads_gone(ctx: JobEnd) -> None:
    """A step job whose read entities (or joints) were deleted is answered now with
    NOT_FOUND, not after its steps (a prediction's scratch world cannot lose them)."""
    job = ctx.job
    if job is None or job.scratch:
        return
    world = job.world or ctx.world
    gone = [name for name in job.read or () if name not in world.entities]
    gone += [name for name in job.read_joints or () if name not in world.joints.by_name]
    if gone:
        ctx.end_job()
        ctx.replies.error(job.call, NotFoundError(
            f"{brief(gone[0])}, which this step request reads, was deleted after "
            f"{job.done} of {job.total} steps", {"missing": gone[:100],
                                                 "steps_done": job.done}))
