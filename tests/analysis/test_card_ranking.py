"""The report card's ranking, recommendation and files, on measures given here."""

from __future__ import annotations

import json
from pathlib import Path

from galton.analysis.report_card import CRITERIA, CardResults, rank_of, ranking, recommend
from galton.analysis.report_card_outputs import write_card_outputs


def card() -> CardResults:
    small = {c.key: None for c in CRITERIA} | {
        "idle_rss_mb": 90.0, "idle_cpu_percent": 0.5, "step_zmq_ms": 0.2, "laws_passed": 12.0,
        "board_chi2_median": 9.0, "physics_errors": 0.0, "predict_ms": 40.0}
    faithful = {c.key: None for c in CRITERIA} | {
        "idle_rss_mb": 150.0, "idle_cpu_percent": 0.5, "step_zmq_ms": 0.4,
        "laws_passed": 18.0, "board_chi2_median": 6.0, "physics_errors": 0.0,
        "predict_ms": 80.0}
    return CardResults({"light": small, "exact": faithful},
                       curves={"light": {1: 50.0, 100: 5.0}, "exact": {1: 20.0, 100: 2.0}},
                       versions={"light": "1.0", "exact": "2.0"}, config={"quick": True})


def test_rankings_follow_each_criterions_direction() -> None:
    results = card()
    assert ranking(results, "idle_rss_mb") == ["light", "exact"]  # lower is better
    assert ranking(results, "laws_passed") == ["exact", "light"]  # higher is better
    assert rank_of(results, "idle_cpu_percent", "exact") == 1  # a tie shares first place
    assert ranking(results, "fork_ms") == ["light", "exact"]  # unmeasured: as listed


def test_each_use_gets_the_engine_that_leads_its_criteria() -> None:
    results = card()
    embedded = recommend(results, "embedded predictor on a 2-core board computer")
    assert embedded.engine == "light"
    assert {"idle_rss_mb", "step_zmq_ms", "predict_ms"} <= set(embedded.wins)
    offline = recommend(results, "faithful offline benchmark")
    assert offline.engine == "exact" and "laws_passed" in offline.wins


def test_the_files_say_what_card_json_holds(tmp_path: Path) -> None:
    results = card()
    files = write_card_outputs(results, tmp_path)
    saved = CardResults.from_dict(json.loads(files["card_json"].read_text()))
    assert saved.measures == results.measures and saved.curves == results.curves
    text = files["card_md"].read_text()
    assert "**embedded predictor on a 2-core board computer: light.**" in text
    assert "| idle memory (RSS, board loaded) | 90 MB (#1) | 150 MB (#2) | light |" in text
    assert ("| idle CPU (board loaded, paused) | 0.5 % of a core (#1) | 0.5 % of a core (#1) "
            "| light, exact |") in text
    page = files["card_html"].read_text()
    assert page.count("data:image/png;base64,") == 1  # the RTF curve, inlined
    assert 'src="http' not in page and "<strong>embedded predictor" in page
