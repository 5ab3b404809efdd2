"""The errors of ``galton.analysis``; every one says what was wrong and what would be right.

::

    AnalysisError                 root: a result cannot be computed from these numbers
    ├── CountsError               a bin-count table has the wrong length or a bad entry
    ├── NoSettledBallsError       no ball settled in a bin: there is no distribution to test
    ├── TooFewBallsError          too few balls for two cells of expected count >= 5
    ├── RecordError               a trial record or results.json field is missing or mistyped
    └── WeightsError              a report card's criteria or uses (--weights FILE) are malformed

The package stays free of other galton packages, so the root derives from ``Exception``;
the client may catch ``AnalysisError`` at its edge beside ``GaltonError``.
"""

from __future__ import annotations


class AnalysisError(Exception):
    """Root of the errors raised by galton.analysis."""


class CountsError(AnalysisError):
    """A table of bin counts has the wrong number of bins, or a negative / non-integer count."""


class NoSettledBallsError(AnalysisError):
    """No ball settled, so expected counts are all zero and chi-squared is undefined."""


class TooFewBallsError(AnalysisError):
    """Merging sparse bins left fewer than two cells, so the merged test has no freedom."""


class RecordError(AnalysisError):
    """A trial record (or results.json) is missing a field, mistyped, or inconsistent."""


class WeightsError(AnalysisError):
    """A report card's criteria-and-uses file is unreadable, names an unknown criterion, or
    gives a field a value it cannot take."""
