"""Summaries over repetitions: per engine configuration, per ball count, and over all counts.

An engine configuration is (engine, board, release); its label is the engine name unless
the results hold several configurations of that engine. Monte Carlo seeds derive from one
base seed and the group's identity, so re-summarising the same records gives the same numbers.
"""

from __future__ import annotations

import statistics
import zlib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from galton.analysis import stats
from galton.analysis.records import LOSS_REASONS, TrialRecord

ConfigKey = tuple[str, str, str]


@dataclass(frozen=True)
class GroupSummary:
    """Trials of one configuration at one ball count (``balls`` None: all counts together)."""

    balls: int | None
    trials: int
    released: int
    settled: int
    lost: int
    unsettled: int
    lost_by_reason: dict[str, int]
    chi2_median: float | None
    chi2_mean: float | None
    trials_over_critical: int
    pooled: stats.GoodnessOfFit | None
    lost_percent_mean: float
    lost_percent_max: float
    lost_percent_pooled: float
    rtf_mean: float | None
    rtf_min: float | None
    rtf_max: float | None
    peak_rss_bytes: int | None
    cpu_percent_mean: float | None


@dataclass(frozen=True)
class EngineSummary:
    """One engine configuration: per-ball-count groups and the pool over all of them."""

    label: str
    engine: str
    engine_version: str
    board: str
    release: str
    settings: dict[str, Any]
    settings_vary: bool
    groups: tuple[GroupSummary, ...]
    overall: GroupSummary

    @property
    def largest(self) -> GroupSummary:
        """The group at the largest ball count tested."""
        return max(self.groups, key=lambda g: g.balls or 0)


def trial_seed(seed: int, *identity: str | int) -> np.random.SeedSequence:
    """A reproducible seed for one group or trial, independent of Python's hash salt."""
    words = [zlib.crc32(str(part).encode()) for part in identity]
    return np.random.SeedSequence([seed, *words])


def score_trial(trial: TrialRecord, draws: int = stats.DEFAULT_DRAWS,
                seed: int = stats.DEFAULT_SEED) -> TrialRecord:
    """A copy with chi2 and p-values filled; left None when no ball settled."""
    if trial.settled == 0:
        return replace(trial, chi2=None, p_asymptotic=None, p_monte_carlo=None)
    rng = np.random.default_rng(
        trial_seed(seed, trial.engine, trial.board, trial.release, trial.balls, trial.repetition))
    return replace(
        trial,
        chi2=stats.chi2_statistic(trial.counts, trial.rows),
        p_asymptotic=stats.p_asymptotic(trial.counts, trial.rows),
        p_monte_carlo=stats.p_monte_carlo(trial.counts, trial.rows, draws, rng),
    )


def score_trials(trials: Iterable[TrialRecord], draws: int = stats.DEFAULT_DRAWS,
                 seed: int = stats.DEFAULT_SEED) -> list[TrialRecord]:
    """Score the trials not yet scored; scored ones are kept as they are."""
    return [t if t.chi2 is not None or t.settled == 0 else score_trial(t, draws, seed)
            for t in trials]


def _mean(values: Sequence[float]) -> float | None:
    return statistics.fmean(values) if values else None


def _present(values: Iterable[float | int | None]) -> list[float]:
    return [float(v) for v in values if v is not None]


def _per_trial_chi2(trials: Sequence[TrialRecord]) -> list[float]:
    """Per-trial chi2 (the paper's statistic) of the trials where a ball settled."""
    return [t.chi2 if t.chi2 is not None else stats.chi2_statistic(t.counts, t.rows)
            for t in trials if t.settled > 0]


def _pooled_test(trials: Sequence[TrialRecord], draws: int,
                 rng: np.random.SeedSequence) -> stats.GoodnessOfFit | None:
    """The test of the counts summed over all trials; None when no ball settled at all."""
    if sum(t.settled for t in trials) == 0:
        return None
    rows = trials[0].rows
    return stats.pooled_over_repetitions([t.counts for t in trials], rows,
                                         draws * stats.POOLED_DRAWS_FACTOR,
                                         np.random.default_rng(rng))


def summarise_group(trials: Sequence[TrialRecord], balls: int | None,
                    draws: int = stats.DEFAULT_DRAWS,
                    rng: np.random.SeedSequence | None = None) -> GroupSummary:
    """Summary statistics of a set of trials (repetitions of one configuration)."""
    chi2s = _per_trial_chi2(trials)
    released = sum(t.balls for t in trials)
    lost = sum(t.lost for t in trials)
    losses = [t.lost_percent for t in trials]
    rtfs = _present(t.rtf for t in trials)
    rss = _present(t.peak_rss_bytes for t in trials)
    critical = stats.critical_value(stats.ALPHA, trials[0].rows)
    return GroupSummary(
        balls=balls,
        trials=len(trials),
        released=released,
        settled=sum(t.settled for t in trials),
        lost=lost,
        unsettled=sum(t.unsettled for t in trials),
        lost_by_reason={r: sum(t.lost_by_reason.get(r, 0) for t in trials) for r in
                        sorted({*LOSS_REASONS, *(k for t in trials for k in t.lost_by_reason)})},
        chi2_median=statistics.median(chi2s) if chi2s else None,
        chi2_mean=_mean(chi2s),
        trials_over_critical=sum(c > critical for c in chi2s),
        pooled=_pooled_test(trials, draws, rng or np.random.SeedSequence(stats.DEFAULT_SEED)),
        lost_percent_mean=statistics.fmean(losses),
        lost_percent_max=max(losses),
        lost_percent_pooled=100.0 * lost / released if released else 0.0,
        rtf_mean=_mean(rtfs),
        rtf_min=min(rtfs) if rtfs else None,
        rtf_max=max(rtfs) if rtfs else None,
        peak_rss_bytes=int(max(rss)) if rss else None,
        cpu_percent_mean=_mean(_present(t.cpu_percent_mean for t in trials)),
    )


def config_key(trial: TrialRecord) -> ConfigKey:
    """What makes trials comparable: same engine, board preset and release mode."""
    return (trial.engine, trial.board, trial.release)


def config_labels(keys: Iterable[ConfigKey]) -> dict[ConfigKey, str]:
    """Engine name as label, qualified by board and release only where the engine repeats."""
    keys = sorted(set(keys))
    engines = [k[0] for k in keys]
    return {k: k[0] if engines.count(k[0]) == 1 else f"{k[0]} [{k[1]}, {k[2]}]" for k in keys}


def summarise_config(trials: Sequence[TrialRecord], label: str,
                     draws: int = stats.DEFAULT_DRAWS,
                     seed: int = stats.DEFAULT_SEED) -> EngineSummary:
    """Summarise one configuration's trials per ball count and over all ball counts."""
    first = trials[0]
    ball_counts = sorted({t.balls for t in trials})
    groups = tuple(
        summarise_group([t for t in trials if t.balls == n], n, draws,
                        trial_seed(seed, *config_key(first), n))
        for n in ball_counts)
    return EngineSummary(
        label=label, engine=first.engine, engine_version=first.engine_version,
        board=first.board, release=first.release, settings=dict(first.settings),
        settings_vary=any(t.settings != first.settings for t in trials),
        groups=groups,
        overall=summarise_group(trials, None, draws, trial_seed(seed, *config_key(first), "all")),
    )


def summarise(trials: Sequence[TrialRecord], draws: int = stats.DEFAULT_DRAWS,
              seed: int = stats.DEFAULT_SEED) -> list[EngineSummary]:
    """One EngineSummary per configuration, sorted by label."""
    labels = config_labels(config_key(t) for t in trials)
    return [summarise_config([t for t in trials if config_key(t) == key], label, draws, seed)
            for key, label in sorted(labels.items(), key=lambda item: item[1])]
