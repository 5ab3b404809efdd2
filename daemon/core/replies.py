"""Answering calls from the physics thread: each reply stamped with the step and sim time
of the world its request named, held to the daemon's max_reply_bytes, and sent exactly once
through ``Call.respond`` (whatever the transport does with it, the physics thread goes on).
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any, Protocol

from galton.daemon.core.reply_limit import too_big
from galton.protocol import RemoteError, Reply, ResultCode, encode_reply, error_reply

if TYPE_CHECKING:
    from galton.daemon.core.calls import Call
    from galton.daemon.world.world import World

log = logging.getLogger("galton.daemon")


class Stamped(Protocol):
    """What a reply reads of the loop: the worlds its stamp comes from, and the clock other
    threads read, brought up to date before each answer."""

    world: World
    side: dict[str, World]

    def refresh_clock(self) -> None: ...


class Replies:
    """The physics thread's replies for one loop."""

    def __init__(self, loop: Stamped, max_reply_bytes: int) -> None:
        self.loop = loop
        self.max_reply_bytes = max_reply_bytes

    def ok(self, call: Call, result: dict[str, Any]) -> None:
        """Answer ``call`` with ``result``; a reply over max_reply_bytes is never sent, the
        call gets RESOURCE_EXHAUSTED instead (daemon/core/reply_limit.py)."""
        world = self._stamping(call)
        data = encode_reply(Reply(ResultCode.OK, result=result, step=world.step_index,
                                  sim_time=world.sim_time))
        if len(data) > self.max_reply_bytes:
            self.error(call, too_big(f"the reply to {call.op or 'this request'}", len(data),
                                     self.max_reply_bytes, "ask for less"))
            return
        send(call, data)

    def error(self, call: Call, error: RemoteError) -> None:
        """Answer ``call`` with ``error``'s code and message."""
        world = self._stamping(call)
        send(call, encode_reply(error_reply(error, world.step_index, world.sim_time)))

    def _stamping(self, call: Call) -> World:
        """The world whose step and sim time a reply carries: the one the request named
        (the live one when it named none, or when that world is gone). The clock other
        threads read is refreshed first: what the client asks next sees what it was told."""
        self.loop.refresh_clock()
        if call.world is None:
            return self.loop.world
        return self.loop.side.get(call.world, self.loop.world)


def send(call: Call, data: bytes) -> None:
    """Hand the reply's bytes to the transport; a transport's failure is logged, never
    raised into the loop."""
    try:
        call.respond(data)
    except Exception:
        log.exception("could not answer a %s request", call.op)
