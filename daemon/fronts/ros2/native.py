"""How a service handler asks the daemon: it yields ``(op, args)`` native requests and is
sent back each one's Reply, so one ROS request may take several native ones without any
thread waiting (the front's driver sends each reply on into the handler)."""

from __future__ import annotations

from collections.abc import Callable, Generator
from typing import Any

from galton.daemon.fronts.ros2 import codes
from galton.protocol import Reply

NativeRequest = tuple[str, dict[str, Any]]
# A handler: the decoded ROS request in, native requests out, the ROS response returned.
Handler = Callable[[Any], Generator[NativeRequest, Reply, Any]]
Asking = Generator[NativeRequest, Reply, dict[str, Any]]


class Refusal(Exception):  # noqa: N818 (a result, not a bug: the response's Result)
    """Ends a handler: its response carries this msg/Result code and message."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(message)
        self.code = code
        self.message = message


def ask(op: str, args: dict[str, Any] | None = None,
        code_of: Callable[[Reply], int | None] | None = None) -> Asking:
    """One native request; its result, or a Refusal with the msg/Result code of its
    failure (``code_of`` may name a service's own code for a reply, else the common one)."""
    reply = yield op, args or {}
    if not reply.ok:
        special = code_of(reply) if code_of is not None else None
        raise Refusal(special if special is not None else codes.result_code(reply.code),
                      reply.message)
    return reply.result
