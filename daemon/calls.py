"""Requests as the physics loop holds them, independent of Zenoh."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass
class Call:
    """One request: which op, its bytes, and how to answer it (exactly once)."""

    op: str
    payload: bytes
    respond: Callable[[bytes], None]
    client: str | None = None  # the sender's id, once the request is decoded


@dataclass
class Task:
    """Work for the physics thread that is no request: e.g. a client's disappearance."""

    run: Callable[[], None]


@dataclass
class RestCheck:
    """Stop a step request early once every body it reads moves slower than ``speed`` m/s,
    looked at every ``every`` steps."""

    speed: float
    every: int


@dataclass
class StepJob:
    """A step or run_until request still in progress; answered when ``remaining`` is 0, or
    earlier once the bodies it reads rest (``rest``)."""

    call: Call
    total: int
    remaining: int
    read: list[str] | None = None  # entities whose states the reply carries, checked up front
    rest: RestCheck | None = None
    read_joints: list[str] | None = None  # 1-DOF joints whose states the reply carries

    @property
    def done(self) -> int:
        return self.total - self.remaining

    def steps_to_next_check(self) -> int:
        """Steps until the next rest check (all remaining ones when there is none)."""
        if self.rest is None:
            return self.remaining
        return min(self.remaining, self.rest.every - self.done % self.rest.every)
