"""Requests as the physics loop holds them, independent of Zenoh."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

if TYPE_CHECKING:
    from galton.daemon.world.futures import FutureSet
    from galton.daemon.world.world import World


class Sampler(Protocol):
    """What a prediction records every ``every`` steps, and the reply it makes of it."""

    every: int

    def take(self, world: World) -> None: ...

    def result(self, steps: int) -> dict[str, Any]: ...


class Driver(Protocol):
    """A side job that is no plain stepping (calibrate's search): it does one chunk of
    work at a time between the live world's steps, and makes the reply when finished."""

    @property
    def finished(self) -> bool: ...

    def advance(self) -> int: ...  # one chunk; returns the steps it took

    def result(self) -> dict[str, Any]: ...

    def close(self) -> None: ...  # release what a chunk left open (the job ended early)


@dataclass
class Call:
    """One request: which op, its bytes, and how to answer it (exactly once)."""

    op: str
    payload: bytes
    respond: Callable[[bytes], None]
    client: str | None = None  # the sender's id, once the request is decoded
    world: str | None = None  # the world it names, once decoded (its reply's stamp)
    # The connection it came on, when the transport has connections (ZeroMQ): a step job
    # is tied to it as to a Zenoh client's token. ``op`` is "" until decoded there.
    peer: str | None = None
    role: str | None = None  # the sender's role where the transport knows it (ZeroMQ)


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
    world: World | None = None  # a side world's (or a prediction's); None: the live world
    sampler: Sampler | None = None  # a prediction's sampling
    step_cost: float = 1e-4  # seconds per step, for chunks of a side world's steps
    scratch: bool = False  # its world is a prediction's copy, closed when the job ends
    source: World | None = None  # the world a prediction copied: pausing it ends the job
    futures: FutureSet | None = None  # a prediction's futures (world: the first of them)
    driver: Driver | None = None  # a side job's own work in place of plain steps

    @property
    def done(self) -> int:
        return self.total - self.remaining

    def release(self) -> None:
        """Close a prediction's copy of its world once the job is answered or ended."""
        if self.driver is not None:
            self.driver.close()
        if self.futures is not None:
            self.futures.close()
        elif self.scratch and self.world is not None:
            self.world.engine.close()

    def steps_to_next_check(self) -> int:
        """Steps until the next rest check (all remaining ones when there is none)."""
        left = self.remaining
        if self.rest is not None:
            left = min(left, self.rest.every - self.done % self.rest.every)
        if self.sampler is not None:
            left = min(left, self.sampler.every - self.done % self.sampler.every)
        return left


def smoothed_step_cost(cost: float, seconds: float, count: int) -> float:
    """A running estimate of seconds per step after ``count`` steps took ``seconds``: it
    sizes the next chunk of steps, so one slow chunk moves it only a fifth of the way."""
    return 0.8 * cost + 0.2 * max(seconds / count, 1e-7)


class Inbox(Protocol):
    """Where requests wait for the physics thread: a queue.SimpleQueue, or with a polled
    front (ZeroMQ) a daemon/core/inbox.PolledInbox that also polls its sockets."""

    def put(self, item: Call | Task | None) -> None: ...

    def get(self, block: bool = True, timeout: float | None = None) -> Call | Task | None: ...

    def get_nowait(self) -> Call | Task | None: ...


# What the core publishes goes out as (topic, msgpack bytes) to every front
# (``Fronts.publish``), which puts it on ``galton/<instance>/<topic>`` or ignores it.
Publish = Callable[[str, bytes], None]
TELEMETRY = "telemetry"
EVENTS = "events"  # a state stream's topic is ``states/<id>`` (protocol.keys.STREAMS_CHUNK)


class CallPort(Protocol):
    """The core's call interface: all a front (daemon/fronts/) may reach of the core. Calls
    in (answered exactly once through ``Call.respond``), and word that a client has gone."""

    def dispatch(self, call: Call) -> None:
        """Hand a request to the physics thread, or answer a fast one on the caller's."""

    def lose_client(self, client: str) -> None:
        """A client has gone (its token or connection): end what it held, on the physics
        thread."""


class PolledSource(Protocol):
    """A front whose sockets the physics thread polls itself (ZeroMQ): no thread hand-off
    for its calls. ``daemon/core/inbox.PolledInbox`` takes turns between it and the queue."""

    def wake(self) -> None:
        """Called from any thread: make a waiting ``wait`` return."""

    def wait(self, timeout: float | None) -> None:
        """Block until the source may have input, it is woken, or ``timeout`` seconds."""

    def receive(self, gone: Callable[[str], Task]) -> list[Call | Task]:
        """What is readable now, without blocking (closed connections as ``gone`` Tasks)."""
