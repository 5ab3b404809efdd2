"""The look-ahead operations, predict, calibrate and compare (whose trigger may start a
calibration): thin adapters over daemon/core/predict.py, daemon/core/calibrate.py and
daemon/world/pose_compare.py; predictions and calibrations run as side jobs of the physics
thread (daemon/core/surprise_calibration.py starts a trigger's)."""

from __future__ import annotations

from typing import Any

from galton.daemon.core import calibrate as calibration
from galton.daemon.core import predict as prediction
from galton.daemon.core import surprise_calibration
from galton.daemon.core.calls import Call
from galton.daemon.core.context import PredictContext
from galton.daemon.ops.binding import handles
from galton.daemon.world import pose_compare
from galton.daemon.world.world import World
from galton.protocol import requests as rq
from galton.protocol.operations import Calibrate


@handles("predict")
def predict(ctx: PredictContext, call: Call, request: rq.Predict) -> None:
    prediction.predict(ctx, call, request)


@handles("calibrate")
def calibrate(ctx: PredictContext, call: Call, request: Calibrate) -> None:
    calibration.calibrate(ctx, call, request)


@handles("compare")
def compare(ctx: PredictContext, call: Call, request: rq.Compare) -> dict[str, Any]:
    """Observed poses against the world's; a ``scene`` event with the score (the view
    charts it); a trigger's streak reaching its window suggests a calibration (an event)
    and, with the trigger's ``calibrate``, starts it."""
    world = ctx.world_for(request)
    trigger = request.trigger
    if trigger is not None:
        surprise_calibration.check(world, trigger)  # refused before anything counts
    result = pose_compare.compare(world, request)
    ctx.emit({"kind": "scene", "op": "compare", "world": world.name,
              "step": world.step_index, "score": result["score"],
              "sim_time": world.sim_time})
    if trigger is not None and result["suggested"]:
        ctx.emit(_suggestion(world, request, result))
        if trigger.calibrate is not None:
            result["calibrating"] = surprise_calibration.start(ctx, world, request)
    ctx.check_job_reads()
    return result


def _suggestion(world: World, request: rq.Compare, result: dict[str, Any]) -> dict[str, Any]:
    """compare's surprise trigger fired: what an architecture needs to start a calibration
    (the bodies, since when the world has been surprised)."""
    assert request.trigger is not None
    return {"kind": "calibration_suggested", "world": world.name, "step": world.step_index,
            "sim_time": world.sim_time, "names": list(request.names),
            "score": result["score"], "streak": result["streak"],
            "since": world.surprise.since, "threshold": request.trigger.threshold,
            "window": request.trigger.window}
