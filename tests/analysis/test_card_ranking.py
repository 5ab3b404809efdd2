"""The report card's intervals, ties, ranks and recommendations, on measures made here
(seeded), and its files agreeing with its card.json."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import binom

from galton.analysis.card_intervals import (
    BoardTrial,
    Measure,
    board_measures,
    count_measure,
    laws_measure,
    mean_measure,
    measure_text,
    median_measure,
)
from galton.analysis.card_paper import paper_rows
from galton.analysis.card_rules import clearly_better, decide, load_rules, ranks
from galton.analysis.errors import WeightsError
from galton.analysis.laws import Check
from galton.analysis.report_card import CardResults, criterion_table, decisions
from galton.analysis.report_card_outputs import write_card_outputs
from galton.analysis.stats import bin_probabilities

RULES = load_rules()


def check(law: str, value: float, tolerance: float = 0.1, theory: float = 0.0) -> Check:
    return Check(law, f"{law} quantity", "m", theory, value, tolerance, "why")


def test_a_median_interval_is_made_of_order_statistics() -> None:
    samples = np.random.default_rng(1).permutation(np.arange(1.0, 101.0))
    assert median_measure(samples) == Measure(50.5, 40.0, 61.0, 100)
    assert median_measure([3.0, 1.0, 2.0]) == Measure(2.0, 1.0, 3.0, 3)  # < 6: the range


def test_means_counts_and_laws_carry_their_intervals() -> None:
    mean = mean_measure([1.0, 2.0, 3.0])
    assert mean.value == 2.0 and mean.low == pytest.approx(2 - 2.484, abs=1e-3)
    none = count_measure(0, 500)
    assert (none.value, none.low, none.n) == (0.0, 0.0, 500)
    assert none.high == pytest.approx(3.68, abs=0.02)  # 0 events: up to ~3.7 by chance
    checks = [check("a", 0.01), check("b", 0.09), check("c", 0.12), check("d", 5.0)]
    assert laws_measure(checks) == Measure(2.0, 1.0, 3.0, 4)  # b and c at the line
    assert measure_text(Measure(7.891, 6.8, 9.12, 4)) == "7.89 [6.8–9.12]"
    assert measure_text(Measure(1385.0, 1200.0, 1490.0, 5), "ms") == "1385 [1200–1490] ms"


def test_noise_ties_and_only_a_clear_gap_ranks() -> None:
    cpu = RULES.criteria["idle_cpu_percent"]  # tie under 1 point of a core
    tight_a, tight_b = Measure(1.066, 1.06, 1.07, 30), Measure(1.033, 1.03, 1.04, 30)
    assert not clearly_better(cpu, tight_b, tight_a)  # apart, but under the threshold
    step = RULES.criteria["step_zmq_ms"]  # tie under 10 %
    fast, slow = Measure(0.63, 0.61, 0.66, 100), Measure(1.7, 1.6, 1.8, 100)
    overlapping = Measure(0.7, 0.5, 0.9, 100)
    assert clearly_better(step, fast, slow) and not clearly_better(step, slow, fast)
    assert not clearly_better(step, fast, overlapping)
    zero = Measure.exact(0.0, 400)
    assert ranks(RULES.criteria["physics_errors"], {"a": zero, "b": zero, "c": None}) == {
        "a": 1, "b": 1, "c": None}
    assert ranks(step, {"a": fast, "b": overlapping, "c": slow}) == {"a": 1, "b": 1, "c": 3}


def board(rng: np.random.Generator, law: np.ndarray, trials: int, balls: int = 100
          ) -> list[BoardTrial]:
    return [BoardTrial(tuple(int(c) for c in rng.multinomial(balls, law)), 0, balls)
            for _ in range(trials)]


def leaning() -> np.ndarray:
    """A board whose balls lean right: Binomial(11, 0.6), w about 0.73."""
    return np.asarray(binom.pmf(np.arange(12), 11, 0.6))


def sampled_card(seed: int, trials: int = 4) -> CardResults:
    """Two engines as a --quick card sees them: a fast faithful one and a slower one
    whose board is as faithful; each figure drawn afresh from the seed."""
    rng = np.random.default_rng(seed)
    card = CardResults(measures={}, config={"seed": seed})
    for engine, slowness in (("fast", 1.0), ("slow", 2.5)):
        trials_kept = board(rng, bin_probabilities(), trials)
        measures = board_measures(trials_kept, "board", seed)
        for key in ("step_zmq_ms", "predict_ms", "fork_ms", "snapshot_ms", "restore_ms"):
            measures[key] = median_measure(slowness * rng.lognormal(0.0, 0.3, 100))
        measures["idle_cpu_percent"] = mean_measure(rng.normal(1.0, 0.3, 30))
        measures["physics_errors"] = count_measure(0, 400)
        card.measures[engine] = measures
        card.trials[engine] = {"paper": trials_kept}
        card.laws[engine] = [check("tower", 0.0), check("free-fall", 0.01)]
    return card


def test_two_quick_cards_on_different_seeds_give_the_same_answers() -> None:
    """The fast engine wins the embedded use each time; the boards, alike, always tie."""
    answers = [{u: d.engine for u, d in decisions(sampled_card(seed), RULES).items()}
               for seed in range(6)]
    assert all(a == answers[0] for a in answers), answers
    assert answers[0]["embedded-predictor"] == "fast"
    assert answers[0]["faithful-benchmark"] is None


def test_a_clearly_worse_board_decides_and_says_by_how_much() -> None:
    card = sampled_card(3)
    card.trials["slow"]["paper"] = board(np.random.default_rng(9), leaning(), 4)
    card.measures["slow"] |= board_measures(card.trials["slow"]["paper"], "board", 3)
    table = criterion_table(card, RULES)
    chosen = decide(RULES, "faithful-benchmark", table, card.engines)
    assert chosen.engine == "fast" and chosen.decisive == ["board_effect_w"]
    assert chosen.margin == pytest.approx(3 / 7)  # w 3 of w, lost 2, errors 2 measured


def test_no_clear_winner_says_why() -> None:
    card = sampled_card(0)
    chosen = decisions(card, RULES)["faithful-benchmark"]
    assert chosen.engine is None and chosen.margin == 0.0
    assert "tie on every criterion" in chosen.why


def test_a_weights_file_replaces_the_uses_and_is_checked(tmp_path: Path) -> None:
    mine = tmp_path / "weights.toml"
    mine.write_text("[decision]\nmin_margin = 0.3\n[criteria.idle_cpu_percent]\n"
                    "threshold = 0.01\n[uses.tiny]\ntitle = 'tiny'\n"
                    "weights = { idle_cpu_percent = 1 }\n")
    rules = load_rules(mine)
    assert list(rules.uses) == ["tiny"] and rules.min_margin == 0.3
    assert rules.criteria["idle_cpu_percent"].threshold == 0.01
    assert rules.criteria["idle_cpu_percent"].unit == "% of a core"  # the rest kept
    mine.write_text("[uses.bad]\nweights = { idle_cpu = 1 }\n")
    with pytest.raises(WeightsError, match="did you mean 'idle_cpu_percent'"):
        load_rules(mine)
    mine.write_text("[criteria.made_up]\ntitle = 'x'\n")
    with pytest.raises(WeightsError, match="must be a law criterion"):
        load_rules(mine)


def test_the_files_say_what_card_json_holds(tmp_path: Path) -> None:
    card = sampled_card(1)
    card.laws["slow"][0] = check("tower", 1.17, tolerance=0.005)
    files = write_card_outputs(card, tmp_path, law_links=["laws/report.md"])
    body = json.loads(files["card_json"].read_text())
    assert CardResults.from_dict(body).measures == card.measures
    for engine_measures in body["measures"].values():
        for value in engine_measures.values():
            assert value is None or set(value) == {"value", "low", "high", "n"}
    embedded = body["uses"]["embedded-predictor"]
    assert embedded["engine"] == "fast" and embedded["margin"] >= RULES.min_margin
    assert {d["criterion"] for d in embedded["decisive"]} >= {"step_zmq_ms"}
    assert body["uses"]["faithful-benchmark"]["engine"] is None
    assert body["criteria"]["physics_errors"]["ranks"] == {"fast": 1, "slow": 1}
    assert body["uses"]["stacking-robot"]["criteria"]["stacking_laws"]["ranks"] == {
        "fast": 1, "slow": 2}
    text = files["card_md"].read_text()
    assert "**embedded predictor on a 2-core board computer: fast**" in text
    assert "**faithful offline benchmark (the paper's question): no clear winner.**" in text
    assert "| slow | tower | tower quantity | 1.17 m | 0 | ±0.005 |" in text
    assert "[laws/report.md](laws/report.md)" in text
    page = files["card_html"].read_text()
    assert page.count("data:image/png;base64,") == 0  # no curve, no law plot here
    assert '<a href="laws/report.md">' in page and "<strong>embedded predictor" in page


def test_the_papers_rows_stand_beside_their_engines_with_what_agrees() -> None:
    """DART's χ² beside Gazebo's: both over the critical value; its balls, unlike
    Gazebo's, not lost."""
    column = {"board_chi2_median": {"dart": Measure(40.6, 33.0, 48.0, 4)},
              "board_lost_percent": {"dart": Measure.exact(0.0, 4)},
              "rtf_100": {"dart": Measure(0.17, 0.16, 0.18, 4)}}
    rows, lines = paper_rows(["dart"], column)
    gazebo = next(r for r in rows if r[0] == "Gazebo Harmonic")
    assert gazebo[1].startswith("dart:") and gazebo[2:6] == ["54.84", "40.6 [33–48]",
                                                             "54.3 %", "0 %"]
    assert next(r for r in rows if r[0] == "Webots")[1] == "ode: not on this card"
    (line,) = lines
    assert "χ² agrees" in line and "balls lost does not agree" in line
    assert "real time agrees" in line  # neither keeps real time with many balls
