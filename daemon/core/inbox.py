"""The physics thread's inbox when a front is polled (ZeroMQ): calls handed over from other
threads (Zenoh's) wait in a queue that wakes the poll, the polled front's are read straight
from its sockets on this thread. The core builds it; no front replaces the loop's inbox."""

from __future__ import annotations

import queue
import time
from collections import deque
from collections.abc import Callable

from galton.daemon.core.calls import Call, PolledSource, Task

NOTHING = object()


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
