"""galton-client report-card's measures, taken for real on a tiny plan (one engine, a few
balls, one law), and the card's files agreeing with its card.json."""

from __future__ import annotations

import json
from pathlib import Path

from galton.analysis.board import BoardSpec
from galton.analysis.report_card import CRITERIA, CardResults, value_text
from galton.client.bench.experiment import ExperimentConfig
from galton.client.report_card import CardPlan, run_card, write_report_card
from galton.client.report_card.pooled import local_trials, pooled_trials
from galton.client.sdk.embedded import EmbeddedDaemon, free_loopback_port

TINY = CardPlan(fidelity_balls=20, repetitions=1, curve=(1,), footprint_s=0.5, round_trips=5,
                world_ops=1, laws=("free-fall",), mesh_balls=10, mesh_repetitions=1)


def test_a_tiny_card_measures_every_criterion(tmp_path: Path) -> None:
    card, laws = run_card(["pybullet"], TINY)
    measures = card.measures["pybullet"]
    missing = [c.key for c in CRITERIA if measures.get(c.key) is None]
    assert not missing, missing
    assert measures["laws_passed"] == 1.0 and measures["physics_errors"] == 0.0
    assert 0 < measures["idle_rss_mb"] < 2000  # type: ignore[operator]
    assert measures["step_zmq_ms"] > 0 and set(card.curves["pybullet"]) == {1, 20}  # type: ignore[operator]
    assert [c.law for c in laws.engines[0].checks] == ["free-fall"]
    files = write_report_card(card, laws, tmp_path)
    assert files["laws/results_json"].exists() and files["card_html"].exists()
    saved = CardResults.from_dict(json.loads(files["card_json"].read_text()))
    text = files["card_md"].read_text()
    for criterion in CRITERIA:
        shown = value_text(saved.measures["pybullet"][criterion.key], criterion.unit)
        assert f"| {criterion.title} | {shown} (#1) |" in text


def test_pool_trials_run_on_a_small_real_pool_and_fall_back_when_none_answers() -> None:
    """Two meshed daemons take the card's Galton trials; a pool whose endpoint nobody
    serves is said so, and the trials run on the engine's own daemon."""
    config = ExperimentConfig(board=BoardSpec.load("small"), engines=("pybullet",),
                              balls=(5,), repetitions=2, max_sim_time=5.0)
    said: list[str] = []
    with EmbeddedDaemon("pybullet", instance="card-pool-1") as first, \
            EmbeddedDaemon("pybullet", instance="card-pool-2",
                           extra_args=["--connect", first.endpoint]), \
            pooled_trials([first.endpoint], ["card-pool-1", "card-pool-2"], 30.0,
                          said.append) as (trials_of, members):
        assert members == ["card-pool-1", "card-pool-2"]
        records = trials_of(None, "pybullet", config)  # type: ignore[arg-type]
    assert [r.repetition for r in records] == [0, 1] and all(r.balls == 5 for r in records)
    with pooled_trials([f"tcp/127.0.0.1:{free_loopback_port()}"], None, 5.0,
                       said.append) as (trials_of, members):
        assert members == [] and trials_of is local_trials
    assert "no pool daemon answers" in said[-1]
