"""The time-control operations' handlers: play, set_rtf, pause, stop, step, run_until,
reset, load_world and status as the physics thread answers it. Thin adapters: the state
machine they drive lives in daemon/core/time_control.py, beside the step jobs and the
pacer it shares with the loop."""

from __future__ import annotations

from typing import Any

from galton.daemon.core import time_control as clock
from galton.daemon.core.calls import Call
from galton.daemon.core.context import TimeContext
from galton.daemon.ops.binding import handles
from galton.protocol import requests as rq


@handles("status")
def status(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return clock.status(ctx, call, request)


@handles("play")
def play(ctx: TimeContext, call: Call, request: rq.Play) -> dict[str, Any]:
    return clock.play(ctx, call, request)


@handles("set_rtf")
def set_rtf(ctx: TimeContext, call: Call, request: rq.SetRtf) -> dict[str, Any]:
    return clock.set_rtf(ctx, call, request)


@handles("pause")
def pause(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return clock.pause(ctx, call, request)


@handles("stop")
def stop(ctx: TimeContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return clock.stop(ctx, call, request)


@handles("step")
def step(ctx: TimeContext, call: Call, request: rq.Step) -> None:
    clock.step(ctx, call, request)


@handles("run_until")
def run_until(ctx: TimeContext, call: Call, request: rq.RunUntil) -> dict[str, Any] | None:
    return clock.run_until(ctx, call, request)


@handles("reset")
def reset(ctx: TimeContext, call: Call, request: rq.Reset) -> dict[str, Any]:
    return clock.reset(ctx, call, request)


@handles("load_world")
def load_world(ctx: TimeContext, call: Call, request: rq.LoadWorld) -> dict[str, Any]:
    return clock.load_world(ctx, call, request)
