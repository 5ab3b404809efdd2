"""The short fuzz campaign of the test command: a few thousand seeded requests per engine
against a real daemon of its own, each checked by ``galton.client.fuzz`` (one typed reply in time;
a rejected request changes nothing), and the daemon still up at the end."""

from __future__ import annotations

import pytest

from galton.client import Client, EmbeddedDaemon
from galton.client.fuzz.campaign import run_campaign

SHORT_CAMPAIGN = 1500
RESEALED = 10  # re-sealed corrupt snapshots after the requests (issue 35)


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
