"""The SDK's control lease (issue 28), mixed into Client: one client at a time may hold
control of a daemon; while it does, other clients' requests that change or step a world
raise ControlHeldError, and reads stay open to all.

>>> with sim.control():          # take it (ControlHeldError names the holder if taken)
...     sim.spawn(spheres(["ball"], [[0, 0, 1]], radius=0.05))
...     sim.step(500)            # nobody else can step, reset or delete meanwhile
>>> sim.status().controller      # None: released on leaving the block

The lease is tied to this client's life: closing it, or its process dying, releases
control (and ends its long step), so a crashed controller never locks a daemon.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager, suppress
from typing import TYPE_CHECKING

from galton.protocol import GaltonError
from galton.protocol import requests as rq
from galton.protocol.replies import ReleaseControlReply, TakeControlReply, decode_result

if TYPE_CHECKING:
    from galton.protocol import Reply


class ControlMethods:
    """Client methods that take and release the daemon's control lease."""

    if TYPE_CHECKING:
        def _send(self, op: str, request: rq.Args, timeout: float | None = None
                  ) -> Reply: ...

    def take_control(self) -> bool:
        """Hold control of the daemon until ``release_control``, or until this client
        closes or its process dies. True when taken now, False when this client already
        held it; ControlHeldError (naming the holder) when another client holds it."""
        return decode_result(TakeControlReply, self._send("take_control", rq.NoArgs()).result).taken

    def release_control(self) -> bool:
        """Give control back: True when this client held it, False when nobody did;
        ControlHeldError when another client holds it."""
        reply = self._send("release_control", rq.NoArgs())
        return decode_result(ReleaseControlReply, reply.result).released

    @contextmanager
    def control(self) -> Iterator[None]:
        """Hold control for the block. Leaving it releases control (unless this client
        already held it on entering); an error raised in the block is never hidden by a
        failure to release (the lease ends with the client anyway)."""
        taken = self.take_control()
        try:
            yield
        except BaseException:
            if taken:
                with suppress(GaltonError):
                    self.release_control()
            raise
        if taken:
            self.release_control()
