"""compare's trigger with ``calibrate``: the paper's loop closed in the daemon. When a
world's streak of surprising comparisons reaches the trigger's window, the daemon starts
``calibrate`` itself over the streak's own observations (each comparison's observed poses at
its sim time, the first one the start), as a job like any calibrate: progress events, ended
by ``pause``; a ``calibration_started`` event when it starts and a
``calibration_finished`` event when it ends (its result, or the error that ended it), and
with ``apply`` the fitted values set in the world."""

from __future__ import annotations

from typing import Any

import numpy as np

from galton.daemon.core.calibrate import calibrate
from galton.daemon.core.calls import Call
from galton.daemon.core.context import PredictContext
from galton.daemon.core.fit_params import parameters
from galton.daemon.world.world import World
from galton.protocol import RemoteError, pack_f64
from galton.protocol import requests as rq
from galton.protocol.envelope import decode_reply
from galton.protocol.operations import Calibrate


def check(world: World, trigger: rq.Trigger) -> None:
    """A trigger's calibration refused whole before the comparison counts: each parameter
    must be one this world can fit (the typed refusals of ``calibrate``'s ``fit``)."""
    if trigger.calibrate is not None:
        parameters(world, trigger.calibrate.fit)


def start(ctx: PredictContext, world: World, request: rq.Compare) -> bool:
    """Start the calibration of ``world`` over its streak's observations; False, and a
    ``calibration_finished`` event saying why, when it cannot start (another step request
    running, too few samples, ...)."""
    assert request.trigger is not None and request.trigger.calibrate is not None
    order = _request(world, request.trigger.calibrate, request.world)
    head = {"world": world.name}
    call = Call(op="calibrate", payload=b"", respond=lambda data: _ended(ctx, head, data),
                world=request.world if isinstance(request.world, str) else None)
    ctx.emit({"kind": "calibration_started", **head, "step": world.step_index,
              "sim_time": world.sim_time, "names": list(order.names),
              "samples": len(world.surprise.samples), "fit": dict(order.fit)})
    try:
        calibrate(ctx, call, order)
    except RemoteError as error:
        ctx.emit({"kind": "calibration_finished", **head, "error": error.code.name,
                  "message": error.message})
        return False
    return True


def _request(world: World, watch: rq.TriggerCalibration, name: Any) -> Calibrate:
    """The streak's observations as a calibrate request (times from the first sample)."""
    samples = world.surprise.samples
    times = np.array([s.sim_time for s in samples], float) - samples[0].sim_time
    poses = np.concatenate([s.poses for s in samples])
    first = samples[0].twists
    return Calibrate(names=list(samples[0].names), times=pack_f64(times),
                     poses=pack_f64(poses), fit=dict(watch.fit),
                     twists=None if first is None else pack_f64(first), apply=watch.apply,
                     max_predictions=watch.max_predictions, population=watch.population,
                     seed=watch.seed, world=name)


def _ended(ctx: PredictContext, head: dict[str, Any], data: bytes) -> None:
    """The job's reply, as the ``calibration_finished`` event (nobody else waits for it)."""
    reply = decode_reply(data)
    if reply.ok:
        ctx.emit({"kind": "calibration_finished", **head, **reply.result})
    else:
        ctx.emit({"kind": "calibration_finished", **head, "error": reply.code.name,
                  "message": reply.message})
