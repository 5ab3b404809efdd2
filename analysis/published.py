"""The paper's published results (Table 2, Fig. 4), kept as data to print beside ours.

These are figures quoted from the paper, not measured by this project. The paper does not
say how many balls its chi-squared values used, how its ten repetitions were combined, or
how it treated bins with expected counts below 5.
"""

from __future__ import annotations

from dataclasses import dataclass

SOURCE = "The Galton Machine and the Quest for a Robotics Simulator, Table 2 and Fig. 4"
PUBLISHED_LABEL = "published (paper)"
PAPER_CRITICAL_VALUE = 19.68
PAPER_DOF = 11
PAPER_ALPHA = 0.05
PAPER_REPETITIONS = 10


@dataclass(frozen=True)
class PublishedRow:
    """One simulator's row as the paper gives it; RTF as its words and its numeric range."""

    simulator: str
    chi2: float
    lost_percent: float
    rtf_text: str
    rtf_low: float | None
    rtf_high: float | None


PUBLISHED_TABLE2: tuple[PublishedRow, ...] = (
    PublishedRow("Webots", 16.64, 0.4, "≈ 1.0 at every ball count, both computers", 1.0, 1.0),
    PublishedRow("CoppeliaSim 4.3.0", 61.64, 0.0,
                 "0.57–0.77 (computer 1), 1.0 (computer 2)", 0.57, 1.0),
    PublishedRow("Gazebo Harmonic", 54.84, 54.3,
                 "falls as balls grow; peak ≈ 0.48 with one ball", None, 0.48),
)
