"""Step requests that wait for the running one (issue 35, item 10: twenty clients sending
`step(1)` were 99.5 % refused, and stepping fell from 1,432 to 33 steps/s).

A `step` or `run_until` that arrives while another step request runs waits here, in arrival
order. The queue is shared fairly (issue 46: twenty clients pipelining step(1) filled it,
and a polite client's steps were refused 422 times of 596): one client (its ZeroMQ
connection, else its id; anonymous requests count as one) has at most
MAX_QUEUED_PER_CLIENT waiting; past MAX_QUEUED_STEPS in all, only a client with none waiting
still gets in, up to MAX_QUEUED_HARD. Beyond those it is RESOURCE_LIMIT. When the running request
ends, the next is handled as if it arrived then: every check runs again against the world
as it is then (a deleted body, a faulted or playing world, another client's control are
refused then, as they would be now). `pause`, `stop` and `reset` of its world and
`load_world` end the waiting ones (OPERATION_FAILED, ``steps_done`` 0); a client that goes
loses its own without a reply (a ``steps_dropped`` event says how many). `predict` never
waits: INCORRECT_STATE while a step runs.
"""

from __future__ import annotations

from collections import deque

from galton.daemon.core.calls import Call
from galton.protocol import IncorrectStateError, ResourceLimitError

MAX_QUEUED_STEPS = 64  # step requests waiting at once, all clients and worlds together
MAX_QUEUED_PER_CLIENT = 4  # of them, one client's
MAX_QUEUED_HARD = 256  # with a place kept for each client that has none waiting


class StepBusyError(IncorrectStateError):
    """A step request met a running one: the loop queues it (``StepQueue.hold``)."""


class StepQueue:
    """The step requests waiting for the running one, oldest first."""

    def __init__(self) -> None:
        self.calls: deque[Call] = deque()

    def __len__(self) -> int:
        return len(self.calls)

    def hold(self, call: Call) -> None:
        """Queue ``call`` behind the others, or RESOURCE_LIMIT past the client's share or
        the queue's bounds (module docstring)."""
        mine = sum(1 for waiting in self.calls if _owner(waiting) == _owner(call))
        if mine >= MAX_QUEUED_PER_CLIENT:
            raise ResourceLimitError(
                f"this client has {mine} step requests waiting already, at most "
                f"{MAX_QUEUED_PER_CLIENT} (the queue is shared): send this one after a reply",
                {"limit": "queued_steps_per_client", "max": MAX_QUEUED_PER_CLIENT})
        full = MAX_QUEUED_STEPS if mine else MAX_QUEUED_HARD
        if len(self.calls) >= full:
            raise ResourceLimitError(
                f"{len(self.calls)} step requests are already waiting for the running one; "
                "send this one after a reply", {"limit": "queued_steps", "max": full})
        self.calls.append(call)

    def take(self) -> Call | None:
        """The oldest waiting request, if any."""
        return self.calls.popleft() if self.calls else None

    def head(self) -> Call | None:
        """The oldest waiting request, left waiting until ``done`` (its turn)."""
        return self.calls[0] if self.calls else None

    def done(self, call: Call) -> None:
        """``call``, the head, has had its turn."""
        if self.calls and self.calls[0] is call:
            self.calls.popleft()

    def must_wait(self, call: Call) -> bool:
        """Whether a step request must wait behind others even with no job running: one
        that arrives before the waiting ones had their turn goes behind them."""
        return bool(self.calls) and self.calls[0] is not call

    def drop_client(self, client: str) -> list[Call]:
        """Take out the requests of a client that has gone (by its connection over ZeroMQ,
        else by its id)."""
        dropped = [c for c in self.calls if _owner(c) == client]
        self.calls = deque(c for c in self.calls if _owner(c) != client)
        return dropped

    def end_for(self, world: str, live: str) -> list[Call]:
        """Take out the requests that step the world named ``world`` (``live``: the live
        world's name, which a request naming no world steps)."""
        ended = [c for c in self.calls if (c.world or live) == world]
        self.calls = deque(c for c in self.calls if (c.world or live) != world)
        return ended


def _owner(call: Call) -> str | None:
    """Who sent a request: its connection over ZeroMQ, else its client id (None: anonymous)."""
    return call.peer if call.peer is not None else call.client
