"""Where calls come in: ``Intake``, the core's call interface (``CallPort``) that every front
is opened on, and the physics thread's inbox behind it. With a polled front (ZeroMQ) the
inbox is a ``PolledInbox``: calls handed over from other threads (Zenoh's) wait in a queue
that wakes the poll, the polled front's are read straight from its sockets on this thread.
The core builds it; no front replaces the loop's inbox."""

from __future__ import annotations

import queue
import time
from collections import deque
from collections.abc import Callable

from galton.daemon.core.calls import Call, Inbox, PolledSource, Task
from galton.protocol.operations import OPERATIONS

NOTHING = object()


class Intake:
    """The core's ``CallPort``: a fast call (status) is answered on the caller's thread by
    ``answer_fast``, any other waits in ``inbox`` for the physics thread, and a client's
    going becomes a Task there (``gone``)."""

    def __init__(self, polled: PolledSource | None, answer_fast: Callable[[Call], bool],
                 gone: Callable[[str], None]) -> None:
        self.answer_fast = answer_fast
        self.gone = gone
        self.inbox: Inbox = (PolledInbox(polled, self.gone_task) if polled is not None
                             else queue.SimpleQueue())

    def dispatch(self, call: Call) -> None:
        """Any thread: answer a fast call here (unless it asks the physics thread, as a
        side world's status does), else hand it to the physics thread."""
        declared = OPERATIONS.get(call.op)
        if declared is None or not declared.fast or not self.answer_fast(call):
            self.inbox.put(call)

    def lose_client(self, client: str) -> None:
        """Any thread: a client has gone; what it held ends on the physics thread."""
        self.inbox.put(self.gone_task(client))

    def gone_task(self, client: str) -> Task:
        return Task(lambda: self.gone(client))

    def put(self, item: Call | Task | None) -> None:
        """Hand work to the physics thread (None: stop)."""
        self.inbox.put(item)

    def leftovers(self) -> list[Call]:
        """What is still waiting, taken out (the physics thread, stopping, answers it)."""
        found: list[Call] = []
        while True:
            try:
                item = self.inbox.get_nowait()
            except queue.Empty:
                return found
            if isinstance(item, Call):
                found.append(item)


class PolledInbox:
    """Same interface as ``queue.SimpleQueue``: the queue and the polled source take turns."""

    def __init__(self, source: PolledSource, gone: Callable[[str], Task]) -> None:
        self.source = source
        self.gone = gone
        self.queue: queue.SimpleQueue[Call | Task | None] = queue.SimpleQueue()
        self.pending: deque[Call | Task] = deque()
        self._polled_first = False  # whose turn it is: the queue or the polled source

    def put(self, item: Call | Task | None) -> None:
        self.queue.put(item)
        self.source.wake()

    def _take(self) -> object:  # a Call, a Task, None (stop) or NOTHING
        """The next item, or NOTHING: the queue and the polled source take turns, so that
        neither front's load starves the other (only this thread takes from either)."""
        self._polled_first = not self._polled_first
        if self._polled_first:
            item = self._from_source()
            return item if item is not NOTHING or self.queue.empty() else self.queue.get_nowait()
        if not self.queue.empty():
            return self.queue.get_nowait()
        return self._from_source()

    def _from_source(self) -> object:
        if not self.pending:
            self.pending.extend(self.source.receive(self.gone))
        return self.pending.popleft() if self.pending else NOTHING

    def get_nowait(self) -> Call | Task | None:
        item = self._take()
        if item is NOTHING:
            raise queue.Empty
        return item  # type: ignore[return-value]

    def get(self, block: bool = True, timeout: float | None = None) -> Call | Task | None:
        if not block:
            return self.get_nowait()
        deadline = None if timeout is None else time.monotonic() + timeout
        while (item := self._take()) is NOTHING:
            remaining = None if deadline is None else deadline - time.monotonic()
            if remaining is not None and remaining <= 0:
                raise queue.Empty
            self.source.wait(remaining)  # receive() has just looked: see ZmqFront.wait
        return item  # type: ignore[return-value]
