"""The state streams' operations, stream_states and close_stream: thin adapters over
daemon/world/state_streams.py, which samples and publishes them (world/ imports nothing of
ops/)."""

from __future__ import annotations

from typing import Any

from galton.daemon.core.calls import Call
from galton.daemon.core.context import StreamContext
from galton.daemon.ops.binding import handles
from galton.daemon.world import state_streams
from galton.protocol import requests as rq


@handles("stream_states")
def stream_states(ctx: StreamContext, call: Call, request: rq.StreamStates) -> dict[str, Any]:
    return state_streams.stream_states(ctx, call, request)


@handles("close_stream")
def close_stream(ctx: StreamContext, call: Call, request: rq.CloseStream) -> dict[str, Any]:
    return state_streams.close_stream(ctx, call, request)
