"""galton-client report-card's measures, taken for real on a tiny plan (one engine, a few
balls, one law), and the card's files agreeing with its card.json."""

from __future__ import annotations

import json
from pathlib import Path

from galton.analysis.report_card import CRITERIA, CardResults, value_text
from galton.client.report_card import CardPlan, run_card, write_report_card

TINY = CardPlan(fidelity_balls=20, repetitions=1, curve=(1,), footprint_s=0.5, round_trips=5,
                world_ops=1, laws=("free-fall",))


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
