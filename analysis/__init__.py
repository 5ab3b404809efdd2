"""Statistics, summaries, verdicts, reports and plots of the Galton-board benchmark.

Pure computation on numbers and records: no simulator, network or other galton package is
imported here. Start from ``write_outputs(ExperimentResults, out_dir)``.
"""

from galton.analysis.compare import Homogeneity, homogeneity
from galton.analysis.errors import (
    AnalysisError,
    CountsError,
    NoSettledBallsError,
    RecordError,
    TooFewBallsError,
)
from galton.analysis.outputs import (
    REPORT_MD,
    RESULTS_CSV,
    RESULTS_JSON,
    score_results,
    write_outputs,
)
from galton.analysis.plots import plot_all, plot_histograms, plot_resources, plot_rtf
from galton.analysis.published import PUBLISHED_LABEL, PUBLISHED_TABLE2, PublishedRow
from galton.analysis.records import (
    LOSS_REASONS,
    RELEASE_MODES,
    ExperimentResults,
    TrialRecord,
)
from galton.analysis.report import render_report, write_csv
from galton.analysis.stats import (
    ALPHA,
    GoodnessOfFit,
    PooledTails,
    chi2_statistic,
    critical_value,
    detectable_effect,
    effect_size,
    expected_counts,
    goodness_of_fit,
    p_asymptotic,
    p_monte_carlo,
    p_pooled_tails,
    paper_test_size,
    pass_rate,
    pool_tails,
    pooled_over_repetitions,
    sum_over_repetitions,
)
from galton.analysis.summary import (
    EngineSummary,
    GroupSummary,
    score_trial,
    score_trials,
    summarise,
)
from galton.analysis.verdict import Check, Verdict, judge, judge_all

__all__ = [
    "ALPHA",
    "LOSS_REASONS",
    "PUBLISHED_LABEL",
    "PUBLISHED_TABLE2",
    "RELEASE_MODES",
    "REPORT_MD",
    "RESULTS_CSV",
    "RESULTS_JSON",
    "AnalysisError",
    "Check",
    "CountsError",
    "EngineSummary",
    "ExperimentResults",
    "GoodnessOfFit",
    "GroupSummary",
    "Homogeneity",
    "NoSettledBallsError",
    "PooledTails",
    "PublishedRow",
    "RecordError",
    "TooFewBallsError",
    "TrialRecord",
    "Verdict",
    "chi2_statistic",
    "critical_value",
    "detectable_effect",
    "effect_size",
    "expected_counts",
    "goodness_of_fit",
    "homogeneity",
    "judge",
    "judge_all",
    "p_asymptotic",
    "p_monte_carlo",
    "p_pooled_tails",
    "paper_test_size",
    "pass_rate",
    "plot_all",
    "plot_histograms",
    "plot_resources",
    "plot_rtf",
    "pool_tails",
    "pooled_over_repetitions",
    "render_report",
    "score_results",
    "score_trial",
    "score_trials",
    "sum_over_repetitions",
    "summarise",
    "write_csv",
    "write_outputs",
]
