"""Bench results drawn from known laws: seeded stand-ins for bench runs in results.json."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from galton.analysis.records import ExperimentResults, TrialRecord

REPETITIONS = 10


def law_trials(engine: str, release: str, balls: int, law: np.ndarray, seed: int,
               lost: int = 0, unsettled: int = 0) -> list[TrialRecord]:
    """Ten repetitions of ``balls`` drawn from ``law``; repetition 0 loses and strands balls."""
    rng = np.random.default_rng(seed)
    trials = []
    for repetition in range(REPETITIONS):
        first = repetition == 0
        missing = lost + unsettled if first else 0
        trials.append(TrialRecord(
            engine=engine, engine_version="x", board="paper", balls=balls,
            repetition=repetition, seed=0, release=release,
            counts=rng.multinomial(balls - missing, law).tolist(),
            settled=balls - missing, lost=lost if first else 0,
            lost_by_reason={"below_floor": lost if first else 0},
            unsettled=unsettled if first else 0))
    return trials


def write_results(folder: Path, trials: list[TrialRecord]) -> Path:
    """``folder``/results.json holding ``trials``; returns the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    ExperimentResults(trials=trials).to_json(folder / "results.json")
    return folder
