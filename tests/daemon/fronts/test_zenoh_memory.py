"""Big requests over the native Zenoh front leave the daemon no bigger (issue 46: after a
50 MB request the RSS stayed about 48 MiB up, and grew so with each one: a refused status
kept its payload in a reference cycle until a full collection)."""

from __future__ import annotations

import time

import psutil
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon
from galton.protocol import ResultCode, decode_reply

PAYLOAD_BYTES = 50_000_000  # over the default max_request_bytes (16 MiB): refused
GROWTH_ALLOWED = 30 * 2**20  # one such request held was 48 MiB
DEADLINE_S = 10.0  # Zenoh's buffers are trimmed 0.5 s after a big request


def test_big_refused_requests_leave_the_daemon_no_bigger(
        daemons: dict[str, EmbeddedDaemon]) -> None:
    daemon = start_daemon(daemons, "mujoco")
    assert daemon.process is not None
    process = psutil.Process(daemon.process.pid)
    with Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        sim.status()
        before = process.memory_info().rss
        for op in ("status", "list"):  # the fast path and the physics thread's
            replies = sim.transport.send_raw(op, b"\0" * PAYLOAD_BYTES, 60.0)
            assert [decode_reply(r).code for r in replies] == [ResultCode.RESOURCE_LIMIT]
        deadline = time.monotonic() + DEADLINE_S
        grown = process.memory_info().rss - before
        while grown > GROWTH_ALLOWED and time.monotonic() < deadline:
            time.sleep(0.1)  # polling the process's RSS until the trim (0.5 s after) lands
            grown = process.memory_info().rss - before
        assert sim.status().instance == daemon.instance
    assert grown <= GROWTH_ALLOWED, f"RSS grew {grown / 2**20:.0f} MiB"
