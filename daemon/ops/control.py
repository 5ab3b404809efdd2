"""The control lease's operations, take_control and release_control: thin adapters over
daemon/access/lease.py, which holds the lease (access/ imports nothing of ops/)."""

from __future__ import annotations

from typing import Any

from galton.daemon.access import lease
from galton.daemon.core.calls import Call
from galton.daemon.core.context import AccessContext
from galton.daemon.ops.binding import handles
from galton.protocol import requests as rq


@handles("take_control")
def take_control(ctx: AccessContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return lease.take_control(ctx, call, request)


@handles("release_control")
def release_control(ctx: AccessContext, call: Call, request: rq.NoArgs) -> dict[str, Any]:
    return lease.release_control(ctx, call, request)
