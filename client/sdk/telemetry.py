"""Telemetry and events as iterators or callbacks, over a transport's subscriptions
(Zenoh subscribers, or ZeroMQ SUB sockets)."""

from __future__ import annotations

import logging
import queue
from collections.abc import Callable, Iterator
from typing import Any

import msgpack

from galton.client.transport.base import Transport
from galton.client.transport.session import Declared, checked_timeout, undeclare
from galton.protocol import RequestTimeoutError, Telemetry

log = logging.getLogger("galton.client")


class Subscription:
    """A live subscription; ``close()`` (or leaving a ``with``) ends it."""

    def __init__(self, subscriber: Declared) -> None:
        self._subscriber: Declared | None = subscriber

    def close(self) -> None:
        """End the subscription; closing twice is fine."""
        if self._subscriber is not None:
            undeclare(self._subscriber)
            self._subscriber = None

    def __enter__(self) -> Subscription:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _decode_telemetry(data: bytes) -> Telemetry | None:
    try:
        return Telemetry.from_wire(msgpack.unpackb(data))
    except Exception:
        log.warning("ignored an unreadable telemetry sample")
        return None


class TelemetryStream(Subscription):
    """Iterate Telemetry samples; each ``next`` waits at most ``timeout`` seconds."""

    def __init__(self, transport: Transport, timeout: float) -> None:
        self._queue: queue.SimpleQueue[Telemetry] = queue.SimpleQueue()
        self.timeout = checked_timeout(timeout)
        super().__init__(transport.subscribe("telemetry", self._on_sample))

    def _on_sample(self, data: bytes) -> None:
        telemetry = _decode_telemetry(data)
        if telemetry is not None:
            self._queue.put(telemetry)

    def __iter__(self) -> Iterator[Telemetry]:
        return self

    def __next__(self) -> Telemetry:
        return self.next(self.timeout)

    def next(self, timeout: float) -> Telemetry:
        """The next sample, waiting at most ``timeout`` s (RequestTimeoutError after)."""
        wait = checked_timeout(timeout)
        try:
            return self._queue.get(timeout=wait)
        except queue.Empty:
            raise RequestTimeoutError(
                f"no telemetry within {timeout:g} s: is the daemon running, with a "
                "telemetry rate above 0?") from None

    def __enter__(self) -> TelemetryStream:
        return self

    @staticmethod
    def with_callback(transport: Transport,
                      callback: Callable[[Telemetry], None]) -> Subscription:
        def on_sample(data: bytes) -> None:
            telemetry = _decode_telemetry(data)
            if telemetry is not None:
                callback(telemetry)
        return Subscription(transport.subscribe("telemetry", on_sample))


def subscribe_events(transport: Transport,
                     callback: Callable[[dict[str, Any]], None]) -> Subscription:
    def on_sample(data: bytes) -> None:
        try:
            callback(msgpack.unpackb(data))
        except Exception:
            log.exception("event callback failed")
    return Subscription(transport.subscribe("events", on_sample))
