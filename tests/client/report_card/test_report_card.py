"""galton-client report-card's measures, taken for real on a tiny plan (one engine, a few
balls, one law), and the card's files agreeing with its card.json."""

from __future__ import annotations

import json
from pathlib import Path

from typer.testing import CliRunner

from galton.analysis.board import BoardSpec
from galton.analysis.card_intervals import measure_text
from galton.analysis.card_rules import load_rules
from galton.analysis.report_card import CardResults
from galton.client.bench.experiment import ExperimentConfig
from galton.client.cli.app import app
from galton.client.report_card import CardPlan, run_card, write_report_card
from galton.client.report_card.trial_runners import local_trials, pool_trials
from galton.client.sdk.embedded import EmbeddedDaemon, free_loopback_port

TINY = CardPlan(fidelity_balls=20, repetitions=1, curve=(1,), footprint_s=0.5, round_trips=5,
                world_ops=1, laws=("free-fall",), mesh_balls=10, mesh_repetitions=1,
                calibration_seeds=2, calibration_predictions=4)


def test_a_tiny_card_measures_every_criterion(tmp_path: Path) -> None:
    """Every criterion the rules name is measured, each with its interval and its n."""
    rules = load_rules()
    card, laws = run_card(["pybullet"], TINY)
    measures = card.measures["pybullet"]
    measured = [k for k, spec in rules.criteria.items() if not spec.laws]
    missing = [k for k in measured if measures.get(k) is None]
    assert not missing, missing
    assert set(measures) == set(measured)  # nothing measured that no criterion reads
    laws_passed, errors = measures["laws_passed"], measures["physics_errors"]
    assert laws_passed is not None and (laws_passed.value, laws_passed.n) == (1.0, 1)
    assert errors is not None and errors.value == 0.0 and errors.high > 0  # 0, by chance
    rss, step = measures["idle_rss_mb"], measures["step_zmq_ms"]
    assert rss is not None and 0 < rss.low <= rss.value <= rss.high < 2000 and rss.n > 1
    assert step is not None and step.low <= step.value <= step.high and step.n == 5
    assert set(card.curves["pybullet"]) == {1, 20}
    fitted, nominal = measures["calibrated_error_mm"], measures["reference_values_error_mm"]
    assert fitted is not None and nominal is not None and fitted.n == 2
    assert 0 <= fitted.low <= fitted.value <= nominal.value < 50  # mm: the fit can only gain
    assert [c.law for c in laws.engines[0].checks] == ["free-fall"]
    files = write_report_card(card, laws, tmp_path, rules)
    assert files["laws/results_json"].exists() and files["card_html"].exists()
    saved = CardResults.from_dict(json.loads(files["card_json"].read_text()))
    assert saved.measures == card.measures and saved.laws == card.laws
    text = files["card_md"].read_text()
    for key in measured:
        spec = rules.criteria[key]
        assert f"| {spec.title} | {measure_text(measures[key], spec.unit)} (#1) |" in text
    assert "[laws/report.md](laws/report.md)" in text


def test_pool_trials_run_on_a_small_real_pool_and_fall_back_when_none_answers() -> None:
    """Two meshed daemons take the card's Galton trials; a pool whose endpoint nobody
    serves is said so, and the trials run on the engine's own daemon."""
    config = ExperimentConfig(board=BoardSpec.load("small"), engines=("pybullet",),
                              balls=(5,), repetitions=2, max_sim_time=5.0)
    said: list[str] = []
    with EmbeddedDaemon("pybullet", instance="card-pool-1") as first, \
            EmbeddedDaemon("pybullet", instance="card-pool-2",
                           extra_args=["--connect", first.endpoint]), \
            pool_trials([first.endpoint], ["card-pool-1", "card-pool-2"], 30.0,
                          said.append) as (trials_of, members):
        assert members == ["card-pool-1", "card-pool-2"]
        records = trials_of(None, "pybullet", config)  # type: ignore[arg-type]
    assert [r.repetition for r in records] == [0, 1] and all(r.balls == 5 for r in records)
    with pool_trials([f"tcp/127.0.0.1:{free_loopback_port()}"], None, 5.0,
                       said.append) as (trials_of, members):
        assert members == [] and trials_of is local_trials
    assert "no pool daemon answers" in said[-1]


def test_a_bad_weights_file_is_refused_before_anything_is_measured(tmp_path: Path) -> None:
    weights = tmp_path / "weights.toml"
    weights.write_text("[uses.mine]\nweights = { fork = 2 }\n")
    result = CliRunner().invoke(app, ["report-card", "--engines", "mujoco", "--weights",
                                      str(weights), "--out", str(tmp_path / "card")])
    assert result.exit_code == 2 and "did you mean 'fork_ms'" in result.output
    assert not (tmp_path / "card").exists()
