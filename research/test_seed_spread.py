"""``research/seed_spread.py``: how a fidelity verdict depends on the seed.

Its summary line is what docs/research/physics-notebook.md quotes for each 500-ball cell:
the seeds that pass, that rate's 95 % interval and the rate the cell's pooled law predicts.
Here it reads seeded runs of known laws, with the junk lines PyBullet prints between them.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
import seed_spread
from support import tilted_law

from galton.analysis import stats


@pytest.fixture(scope="module")
def spread():
    return seed_spread


def _run(law: np.ndarray, seed: int, engine: str) -> dict:
    """One 500 x 10 run's line as fidelity_inprocess.py prints it, drawn from ``law``."""
    pooled = np.random.default_rng(seed).multinomial(5_000, law)
    return {"engine": engine, "balls": 500, "reps": 10, "mode": "stream", "params": {},
            "surfaces": {}, "seed": seed, "width": 1.66, "lost": 0, "unsettled": 0,
            "pooled": pooled.tolist()}


def _summaries(spread, tmp_path: Path) -> dict[str, str]:
    lines = ["argv[0]="]
    lines += [json.dumps(_run(stats.bin_probabilities(), seed, "fair")) for seed in range(4)]
    lines += [json.dumps(_run(tilted_law(0.12), seed, "wide")) for seed in range(3)]
    path = tmp_path / "runs.jsonl"
    path.write_text("\n".join(lines) + "\n")
    groups: dict = {}
    for run in spread.read_runs([str(path)]):
        groups.setdefault(spread.group_key(run), []).append(run)
    return {key[0]: spread.summary_line(key, runs) for key, runs in groups.items()}


def _percent(pattern: str, line: str) -> float:
    match = re.search(pattern, line)
    assert match, f"{pattern!r} not in {line!r}"
    return float(match.group(1))


def test_summary_counts_passes_and_predicts_the_rate_from_the_pooled_law(
        spread, tmp_path: Path) -> None:
    lines = _summaries(spread, tmp_path)
    assert set(lines) == {"fair", "wide"}
    fair, wide = lines["fair"], lines["wide"]
    fair_passed = sum(stats.p_monte_carlo(_run(stats.bin_probabilities(), s, "fair")["pooled"],
                                          draws=200_000) > stats.ALPHA for s in range(4))
    assert f"{fair_passed}/4 seeds pass" in fair
    assert _percent(r"predicts (\d+) %", fair) >= 90
    assert "0/3 seeds pass (95 % interval 0-71 %" in wide
    assert _percent(r"predicts (\d+) %", wide) < 5
    assert "20000 balls" in fair and "15000 balls" in wide


def _exact_line(law: np.ndarray, seed: int, contact: dict) -> str:
    """One exact_lone_ball.py line: 1,000 lone balls on the paper board under ``contact``."""
    counts = np.random.default_rng(seed).multinomial(1_000, law).tolist()
    return json.dumps({"model": "exact", "board": "paper", "seed": seed, "contact": contact,
                       "balls": 1_000, "bins": {"counts": counts}})


def test_exact_reference_picks_the_constant_law_and_tests_each_group_against_it(
        spread, tmp_path: Path) -> None:
    """Only constant laws at the asked restitution and friction count; a group drawn from
    the exact law agrees with it and one drawn from another law does not."""
    flat = tilted_law(0.05)
    chosen = {"restitution": 0.72, "friction": 0.25, "threshold": 0.2}
    lines = [_exact_line(flat, seed, chosen) for seed in range(8)]
    lines.append(_exact_line(stats.bin_probabilities(), 9, {**chosen, "restitution_at_3": 0.5}))
    lines.append(_exact_line(stats.bin_probabilities(), 10, {**chosen, "friction": 0.5}))
    path = tmp_path / "exact.jsonl"
    path.write_text("\n".join(lines) + "\n")
    exact = spread.exact_counts(str(path), 0.72, 0.25)
    assert exact.sum() == 8_000
    same = [_run(flat, seed, "same") for seed in range(4)]
    other = [_run(stats.bin_probabilities(), seed, "binomial") for seed in range(4)]
    same_text = spread.describe(spread.group_key(same[0]), same, exact)
    other_text = spread.describe(spread.group_key(other[0]), other, exact)
    assert _percent(r"against 8000 exact lone balls: chi2 [\d.]+, 9 df, p ([\d.]+)",
                    same_text) > 0.01
    assert _percent(r"against 8000 exact lone balls: chi2 [\d.]+, 9 df, p ([\d.]+)",
                    other_text) < 0.01
    with pytest.raises(SystemExit, match="no exact paper-board run"):
        spread.exact_counts(str(path), 0.66, 0.25)
