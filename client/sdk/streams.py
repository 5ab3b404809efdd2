"""The SDK's state streams (issue 41), mixed into Client: the poses of all (or named)
entities of a world, published by the daemon at the rate asked (1-60 Hz).

>>> with sim.stream_states(rate=20) as stream:     # every entity of the live world
...     sample = stream.next(timeout=1.0)
...     sample.names, sample.poses                  # (n,) names, (n, 7) x y z qx qy qz qw

The stream is this client's: closing it (or the client) ends it in the daemon. A consumer
slower than the rate loses the oldest samples, never slows the world.
"""

from __future__ import annotations

import contextlib
import logging
import queue
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import msgpack
import numpy as np

from galton.client.sdk.telemetry import Subscription
from galton.client.transport.session import checked_timeout
from galton.protocol import POSE_WIDTH, GaltonError, RequestTimeoutError
from galton.protocol import requests as rq
from galton.protocol.arrays import unpack_f64

if TYPE_CHECKING:
    from galton.client.transport.base import Transport
    from galton.protocol import Reply

log = logging.getLogger("galton.client")
QUEUE_DEPTH = 8  # samples a StateStream keeps for its reader; older ones are dropped


@dataclass(frozen=True)
class StateSample:
    """One sample of a state stream: where each entity was at one step. ``ended`` says
    why the daemon ended the stream (its side world was deleted, or its client went); then
    it holds no poses."""

    stream: str
    seq: int
    world: str
    step: int
    sim_time: float
    state: str
    rtf: float
    names: tuple[str, ...]
    poses: np.ndarray  # (n, 7): x, y, z, qx, qy, qz, qw
    ended: str | None = None

    @classmethod
    def from_wire(cls, wire: dict[str, Any]) -> StateSample:
        names = tuple(str(name) for name in wire.get("names", ()))
        poses = (unpack_f64(wire["poses"], POSE_WIDTH, "poses") if wire.get("poses")
                 else np.zeros((0, POSE_WIDTH)))
        return cls(str(wire["stream"]), int(wire["seq"]), str(wire.get("world", "")),
                   int(wire.get("step", 0)), float(wire.get("sim_time", 0.0)),
                   str(wire.get("state", "")), float(wire.get("rtf", 0.0)), names, poses,
                   wire.get("ended"))


def decode_sample(data: bytes) -> StateSample | None:
    try:
        return StateSample.from_wire(msgpack.unpackb(data))
    except Exception:
        log.warning("ignored an unreadable state sample")
        return None


class StateStream(Subscription):
    """An open state stream: iterate its samples, or give a callback; ``close()`` ends it in
    the daemon too."""

    def __init__(self, owner: StreamMethods, transport: Transport, opened: dict[str, Any],
                 callback: Callable[[StateSample], None] | None, timeout: float) -> None:
        self.stream_id = str(opened["stream"])
        self.key = str(opened["key"])
        self.rate = float(opened["rate"])
        self.world = str(opened["world"])
        self.timeout = checked_timeout(timeout)
        self._owner = owner
        self._queue: queue.Queue[StateSample] = queue.Queue(QUEUE_DEPTH)
        self._callback = callback
        super().__init__(transport.subscribe(str(opened["topic"]), self._on_data, self.key))

    def _on_data(self, data: bytes) -> None:
        sample = decode_sample(data)
        if sample is None:
            return
        if self._callback is not None:
            self._callback(sample)
            return
        while True:
            try:
                self._queue.put_nowait(sample)
                return
            except queue.Full:
                with contextlib.suppress(queue.Empty):
                    self._queue.get_nowait()  # the oldest goes: a reader wants the newest

    def next(self, timeout: float | None = None) -> StateSample:
        """The next sample, waiting at most ``timeout`` s (RequestTimeoutError after)."""
        wait = self.timeout if timeout is None else checked_timeout(timeout)
        try:
            return self._queue.get(timeout=wait)
        except queue.Empty:
            raise RequestTimeoutError(
                f"no state sample within {wait:g} s on stream {self.stream_id} "
                f"({self.rate:g} Hz)") from None

    def __iter__(self) -> Iterator[StateSample]:
        return self

    def __next__(self) -> StateSample:
        return self.next()

    def close(self) -> None:
        """Unsubscribe, and end the stream in the daemon (best effort: a daemon that has
        gone, or a client closed, ends it anyway)."""
        super().close()
        owner, self._owner = self._owner, None  # type: ignore[assignment]
        if owner is not None:
            with contextlib.suppress(GaltonError):
                owner._send("close_stream", rq.CloseStream(stream=self.stream_id))

    def __enter__(self) -> StateStream:
        return self


class StreamMethods:
    """Client methods that open state streams."""

    if TYPE_CHECKING:
        transport: Transport
        timeout: float

        def _send(self, op: str, request: rq.Args, timeout: float | None = None
                  ) -> Reply: ...

        def _check_open(self) -> None: ...

    def stream_states(self, rate: float = 10.0, names: Sequence[str] | None = None,
                      callback: Callable[[StateSample], None] | None = None,
                      timeout: float | None = None) -> StateStream:
        """Open a stream of this world's poses at ``rate`` Hz (1-60): every entity, or
        ``names``. With ``callback``, each sample is handed to it on the transport's thread
        (keep it short); else iterate the stream (``timeout``: each ``next``'s wait)."""
        self._check_open()
        request = rq.StreamStates(rate=rate, names=None if names is None else list(names))
        opened = self._send("stream_states", request).result
        try:
            return StateStream(self, self.transport, opened, callback,
                               self.timeout if timeout is None else timeout)
        except BaseException:
            with contextlib.suppress(GaltonError):
                self._send("close_stream", rq.CloseStream(stream=str(opened["stream"])))
            raise
