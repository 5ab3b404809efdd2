"""The conformance suite: each ``sim`` is a client on a fresh world of the parametrized
engine, reached over Zenoh or over ZeroMQ ipc.

Engine semantics are run once per engine and transport semantics once per transport, not
every product of them (the suite grows with each engine): each engine is paired with one
transport (``TRANSPORT_OF``), the two transports alternating over the engines, and a test
that names no engine runs over both. ``GALTON_EVERY_PAIR=1`` runs every engine over every
transport (on demand)."""

from __future__ import annotations

import os
from collections.abc import Generator, Iterator
from typing import Any

import pytest
from support.daemons import ENGINES, STATED_GAPS

from galton.client import Client, EmbeddedDaemon
from galton.protocol import FeatureUnsupportedError, Reply
from galton.protocol.operations import OPERATIONS
from galton.protocol.replies import decode_result

TRANSPORTS = ("zenoh", "zmq")
# Each engine's transport in the suite: the transports alternate over the engines.
TRANSPORT_OF = {engine: TRANSPORTS[i % len(TRANSPORTS)] for i, engine in enumerate(ENGINES)}
EVERY_PAIR = os.environ.get("GALTON_EVERY_PAIR") == "1"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Keep one transport per engine unless GALTON_EVERY_PAIR=1 (module docstring)."""
    if EVERY_PAIR:
        return
    kept, dropped = [], []
    for item in items:
        params = getattr(item, "callspec", None) and item.callspec.params
        engine = params.get("engine") if params else None
        transport = params.get("transport") if params else None
        paired = engine is None or transport is None or TRANSPORT_OF.get(engine) == transport
        (kept if paired else dropped).append(item)
    if dropped:
        config.hook.pytest_deselected(items=dropped)
        items[:] = kept


@pytest.fixture(params=TRANSPORTS)
def transport(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def sim(daemon: EmbeddedDaemon, transport: str) -> Iterator[Client]:
    """A client over ``transport`` on a fresh, empty, stopped world."""
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint
    with Client(daemon.instance, endpoint, timeout=20.0) as client:
        hold_replies_to_declarations(client)
        client.load_world(daemon.engine)
        yield client


def hold_replies_to_declarations(client: Client) -> None:
    """Every successful reply this client (and its world views, which share its transport)
    gets whose operation declares its reply (protocol/requests.py) is decoded strictly
    against it: a missing, extra or mistyped field fails the test that met it."""
    transport = client.transport
    send = transport.request

    def request(op: str, args: dict[str, Any] | None, *rest: Any) -> Reply:
        reply = send(op, args, *rest)
        declared = OPERATIONS[op].reply if op in OPERATIONS else None
        if reply.ok and declared is not None:
            decode_result(declared, reply.result, exact=True)
        return reply
    transport.request = request  # type: ignore[method-assign]


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[Any]
                              ) -> Generator[None, Any, None]:
    """A test that meets a refusal its engine states (support_daemons.STATED_GAPS) is
    skipped with that refusal; every other failure stays a failure."""
    outcome = yield
    report = outcome.get_result()
    engine = getattr(item, "callspec", None) and item.callspec.params.get("engine")
    if call.excinfo is None or not call.excinfo.errisinstance(FeatureUnsupportedError):
        return
    message = str(call.excinfo.value)
    if any(gap in message for gap in STATED_GAPS.get(str(engine), ())):
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1] or 0, f"stated gap: {message}")
