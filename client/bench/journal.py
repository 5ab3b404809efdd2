"""The trials a bench has finished, saved after each one, so that a run that fails later
(a daemon lost, an engine missing) keeps what it measured."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from galton.analysis.records import ExperimentResults, TrialRecord
from galton.client.bench.experiment import ExperimentConfig, experiment_results
from galton.client.bench.trial import TrialConfig

RESULTS_JSON = "results.json"


class Journal:
    """Finished trials in plan order, rewritten to ``out/results.json`` after each one."""

    def __init__(self, config: ExperimentConfig, out: Path) -> None:
        self.config = config
        self.path = out / RESULTS_JSON
        self._order = {_key(t): i for i, t in enumerate(config.trials())}
        self._done: dict[int, TrialRecord] = {}
        self.executor: dict[str, Any] = {}  # results.json's "executor", once known

    def add(self, trial: TrialConfig, record: TrialRecord) -> None:
        """Keep this trial's record and save every record kept so far."""
        self._done[self._order[_key(trial)]] = record
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.results().to_json(self.path)

    def results(self) -> ExperimentResults:
        records = [self._done[i] for i in sorted(self._done)]
        results = experiment_results(records, self.config, {"partial": True})
        results.executor = dict(self.executor)
        return results

    @property
    def count(self) -> int:
        return len(self._done)


def _key(trial: TrialConfig) -> tuple[str, int, int]:
    return trial.engine, trial.balls, trial.repetition
