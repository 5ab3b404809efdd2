"""Statistics, summaries, verdicts, reports and plots of the Galton-board benchmark.

Pure computation on numbers and records: no simulator, network or other galton package is
imported here. Start from ``write_outputs(ExperimentResults, out_dir)``.

The names below are imported when first used, so that importing one light module (the
board's geometry, the records) does not load scipy and matplotlib: a client that only
builds boards or reads results needs neither. Import from the defining module (for example
``galton.analysis.stats``) where static types matter.
"""

from __future__ import annotations

import importlib
from typing import Any

# Each public name and the module that defines it.
_MODULES: dict[str, tuple[str, ...]] = {
    "same_law": ("Homogeneity", "homogeneity"),
    "errors": (
        "AnalysisError", "CountsError", "NoSettledBallsError", "RecordError",
        "TooFewBallsError",
    ),
    "outputs": ("REPORT_MD", "RESULTS_CSV", "RESULTS_JSON", "score_results", "write_outputs"),
    "plots": ("plot_all", "plot_histograms", "plot_resources", "plot_rtf"),
    "published": ("PUBLISHED_LABEL", "PUBLISHED_TABLE2", "PublishedRow"),
    "records": ("LOSS_REASONS", "RELEASE_MODES", "ExperimentResults", "TrialRecord"),
    "report": ("render_report", "write_csv"),
    "stats": (
        "ALPHA", "GoodnessOfFit", "PooledTails", "chi2_statistic", "critical_value",
        "detectable_effect", "effect_size", "expected_counts", "goodness_of_fit",
        "p_asymptotic", "p_monte_carlo", "p_pooled_tails", "paper_test_size", "pass_rate",
        "pool_tails", "pooled_over_repetitions", "sum_over_repetitions",
    ),
    "summary": ("EngineSummary", "GroupSummary", "score_trial", "score_trials", "summarise"),
    "targets": ("TARGETS_TEXT", "CellVerdict", "cell_verdict", "verdicts", "load_trials"),
    "verdict": ("Check", "Verdict", "judge", "judge_all"),
}
_HOME = {name: module for module, names in _MODULES.items() for name in names}
__all__ = sorted(_HOME)


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use (PEP 562)."""
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module 'galton.analysis' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"galton.analysis.{module}"), name)
    globals()[name] = value
    return value

