"""The short fuzz campaign of the test command: a few thousand seeded requests per engine
against a real daemon of its own, each checked by ``galton.client.fuzz`` (one typed reply in time;
a rejected request changes nothing), and the daemon still up at the end."""

from __future__ import annotations

import pytest

from galton.client import Client, EmbeddedDaemon
from galton.client.fuzz.campaign import run_campaign

SHORT_CAMPAIGN = 1500
RESEALED = 10  # re-sealed corrupt snapshots after the requests (issue 35)
REPLY_LIMIT = 200_000  # low enough that a step's reads of ~2,000 bodies pass it
UNREAD = 600  # requests a ZeroMQ client pipelines without reading


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_a_short_fuzz_campaign_finds_nothing(engine: str) -> None:
    with EmbeddedDaemon(engine, instance=f"fuzz-{engine}", telemetry_rate=20.0) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=30.0) as client:
        report = run_campaign(client, SHORT_CAMPAIGN, seed=22, resealed=RESEALED)
        assert daemon.process is not None and daemon.process.poll() is None
    assert report.requests == SHORT_CAMPAIGN
    assert report.ok, report.to_dict()
    assert report.codes["OK"] > SHORT_CAMPAIGN // 10  # it reached the operations' work
    assert len(report.codes) >= 6  # and many kinds of refusal


def test_the_oversize_and_unread_cases_run_over_zeromq_and_find_nothing() -> None:
    """The campaign in its ZeroMQ mode, with the issue-35 cases: requests over the reply
    limit (every kind, the limit low enough for a step's reads to pass it) and a client
    that never reads. One engine: the limit and the front are the daemon's."""
    with EmbeddedDaemon("mujoco", instance="fuzz-oversize", zmq=True,
                        extra_args=["--limit", f"max_reply_bytes={REPLY_LIMIT}"]) as daemon:
        assert daemon.zmq_endpoint is not None
        with Client(daemon.instance, daemon.zmq_endpoint, timeout=30.0) as client:
            report = run_campaign(client, 20, seed=35, oversize_cases=True, unread=UNREAD)
        assert daemon.process is not None and daemon.process.poll() is None
    assert report.ok, report.to_dict()
    assert report.skipped == []
    assert report.oversize_cases >= 5  # predictions, a render, rays, a step's reads
    assert report.codes["RESOURCE_LIMIT"] >= 5
    assert report.unread_sent > 64  # more than the daemon queues per connection
