"""The Zenoh front's state stream samples (daemon/world/state_streams.py), put on a thread
of their own.

Zenoh's put of a 60 kB sample cost the physics thread about as much as reading the poses
(docs/PERFORMANCE.md, "State streams"); here the physics thread only hands the bytes over.
A sample not yet sent when its stream's next one comes is replaced by it: nothing queues
behind a slow network, and a stream's samples still go out in order.
"""

from __future__ import annotations

import logging
import queue
import threading

from galton.daemon.core.calls import Publish  # (topic "states/<id>", sample bytes)

log = logging.getLogger(__name__)


class SampleSender:
    """Publishes the latest sample of each topic with ``publish`` (which must be safe to call
    off the physics thread, as Zenoh's put is), on a daemon thread started here.

    The hand-over is a ``SimpleQueue`` put: it never waits on a lock the sender's thread
    holds (a Condition's lock cost the physics thread 9 % under load)."""

    def __init__(self, publish: Publish) -> None:
        self._publish = publish
        self._queue: queue.SimpleQueue[tuple[str, bytes] | None] = queue.SimpleQueue()
        self._thread = threading.Thread(target=self._run, name="state-streams", daemon=True)
        self._thread.start()

    def send(self, topic: str, data: bytes) -> None:
        """Hand a sample over (it replaces one of its topic not yet sent)."""
        self._queue.put((topic, data))

    def close(self) -> None:
        """Stop the thread once the latest samples handed over before this are put."""
        self._queue.put(None)
        self._thread.join(timeout=5)

    def _run(self) -> None:
        while True:
            latest: dict[str, bytes] = {}
            item = self._queue.get()
            while item is not None:
                latest[item[0]] = item[1]
                try:
                    item = self._queue.get_nowait()
                except queue.Empty:
                    break
            for topic, data in latest.items():
                self._put(topic, data)
            if item is None:
                return

    def _put(self, topic: str, data: bytes) -> None:
        try:
            self._publish(topic, data)
        except Exception:
            log.exception("could not publish a state stream's sample on %s", topic)
