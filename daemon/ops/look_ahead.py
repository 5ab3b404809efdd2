"""The look-ahead operations, predict and calibrate: thin adapters over
daemon/core/predict.py and daemon/core/calibrate.py, which run them as side jobs of the
physics thread."""

from __future__ import annotations

from galton.daemon.core import calibrate as calibration
from galton.daemon.core import predict as prediction
from galton.daemon.core.calls import Call
from galton.daemon.core.context import PredictContext
from galton.daemon.ops.binding import handles
from galton.protocol import requests as rq
from galton.protocol.operations import Calibrate


@handles("predict")
def predict(ctx: PredictContext, call: Call, request: rq.Predict) -> None:
    prediction.predict(ctx, call, request)


@handles("calibrate")
def calibrate(ctx: PredictContext, call: Call, request: Calibrate) -> None:
    calibration.calibrate(ctx, call, request)
