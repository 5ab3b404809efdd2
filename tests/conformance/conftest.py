"""The conformance suite runs every test over both transports: each ``sim`` is a client on
a fresh world of the parametrized engine, reached over Zenoh or over ZeroMQ ipc."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from galton.client import Client, EmbeddedDaemon

TRANSPORTS = ("zenoh", "zmq")


@pytest.fixture(params=TRANSPORTS)
def transport(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def sim(daemon: EmbeddedDaemon, transport: str) -> Iterator[Client]:
    """A client over ``transport`` on a fresh, empty, stopped world."""
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint
    with Client(daemon.instance, endpoint, timeout=20.0) as client:
        client.load_world(daemon.engine)
        yield client
