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


@dataclass
class StepJob:
    """A step or run_until request still in progress; answered when ``remaining`` is 0."""

    call: Call
    total: int
    remaining: int
    read: list[str] | None = None  # entities whose states the reply carries, checked up front
