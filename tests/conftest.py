"""Shared fixtures: real galton-daemon processes on free loopback ports, one per engine.

Each daemon is started once per test session by its console command, serving Zenoh and a
ZeroMQ ipc socket; a fixture waits for its readiness line and its liveliness token, never
for a fixed time. The conformance suite runs over both transports (tests/conformance/
conftest.py). Before each test the world is replaced by a fresh one (``load_world``), so
tests do not see each other's scene.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from support.daemons import ENGINES, start_daemon

from galton.client import Client, EmbeddedDaemon


@pytest.fixture(scope="session")
def daemons() -> Iterator[dict[str, EmbeddedDaemon]]:
    """Started lazily, one per engine, stopped (SIGTERM) at the end of the session."""
    started: dict[str, EmbeddedDaemon] = {}
    yield started
    for daemon in started.values():
        daemon.stop()


@pytest.fixture(params=ENGINES)
def engine(request: pytest.FixtureRequest) -> str:
    return request.param


@pytest.fixture
def daemon(daemons: dict[str, EmbeddedDaemon], engine: str) -> EmbeddedDaemon:
    return start_daemon(daemons, engine)


@pytest.fixture
def sim(daemon: EmbeddedDaemon) -> Iterator[Client]:
    """A client on a fresh, empty, stopped world of the parametrized engine."""
    with Client(daemon.instance, daemon.endpoint, timeout=20.0) as client:
        client.load_world(daemon.engine)
        yield client


@pytest.fixture
def mujoco_sim(daemons: dict[str, EmbeddedDaemon]) -> Iterator[Client]:
    """A fresh MuJoCo world, for tests that need only one engine."""
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=20.0) as client:
        client.load_world("mujoco")
        yield client
