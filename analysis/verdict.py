"""Is an engine fit to run on board a robot, as the paper asks? Four checks, named thresholds.

* fidelity: every ball count tested meets the fidelity targets, the one definition of a
  pass that ``galton-client check`` applies too (``galton.analysis.targets``: pooled
  Monte Carlo p, median per-trial chi-squared, no ball lost or unsettled);
* loss: balls lost over all trials <= ``MAX_LOST_PERCENT`` of balls released;
* speed: mean RTF at the largest ball count tested >= ``MIN_RTF``;
* footprint: peak RSS <= ``MAX_PEAK_RSS_BYTES`` and mean CPU <= ``MAX_CPU_PERCENT`` (per-count
  means, the highest of them). A measure that was not taken fails its check.
"""

from __future__ import annotations

from dataclasses import dataclass

from galton.analysis.formatting import balls_text
from galton.analysis.summary import EngineSummary
from galton.analysis.targets import TARGETS_TEXT, summary_cells

MAX_LOST_PERCENT = 0.5
MIN_RTF = 1.0
MAX_PEAK_RSS_BYTES = 500_000_000
MAX_CPU_PERCENT = 100.0
SUITABLE = "suitable"
NOT_SUITABLE = "not suitable"

THRESHOLDS_TEXT = (
    f"fidelity: at each ball count, {TARGETS_TEXT} (the targets galton-client check applies); "
    f"loss: <= {MAX_LOST_PERCENT} % of released balls lost; speed: mean RTF >= "
    f"{MIN_RTF} at the largest ball count; footprint: peak RSS <= "
    f"{MAX_PEAK_RSS_BYTES / 1e6:.0f} MB and mean CPU <= {MAX_CPU_PERCENT:.0f} % of one core"
)


@dataclass(frozen=True)
class Check:
    """One criterion: whether it passed and a sentence with the value and the threshold."""

    name: str
    passed: bool
    detail: str


@dataclass(frozen=True)
class Verdict:
    """The verdict on one engine configuration."""

    label: str
    checks: tuple[Check, ...]

    @property
    def suitable(self) -> bool:
        """True only when every check passed."""
        return all(c.passed for c in self.checks)

    @property
    def verdict(self) -> str:
        """'suitable' or 'not suitable'."""
        return SUITABLE if self.suitable else NOT_SUITABLE

    @property
    def reasons(self) -> list[str]:
        """The details of the checks that failed."""
        return [c.detail for c in self.checks if not c.passed]


def check_fidelity(summary: EngineSummary) -> Check:
    """Every ball count meets the fidelity targets (``galton.analysis.targets``)."""
    missed = [cell.miss_text() for cell in summary_cells(summary) if not cell.passed]
    if not missed:
        return Check("fidelity", True, f"every ball count meets the targets ({TARGETS_TEXT})")
    return Check("fidelity", False, "targets missed at " + "; ".join(missed))


def check_loss(summary: EngineSummary) -> Check:
    """Lost balls over all trials within the allowance."""
    lost = summary.overall.lost_percent_pooled
    passed = lost <= MAX_LOST_PERCENT
    return Check("loss", passed, f"{lost:.2f} % of balls lost (limit {MAX_LOST_PERCENT} %)")


def check_speed(summary: EngineSummary) -> Check:
    """Mean real-time factor at the largest ball count tested."""
    group = summary.largest
    if group.rtf_mean is None:
        return Check("speed", False, f"RTF not measured at {balls_text(group.balls)}")
    passed = group.rtf_mean >= MIN_RTF
    return Check("speed", passed,
                 f"mean RTF {group.rtf_mean:.3g} at {balls_text(group.balls)} (need >= {MIN_RTF})")


def check_footprint(summary: EngineSummary) -> Check:
    """Peak memory and CPU within what an on-board computer can spare."""
    rss = summary.overall.peak_rss_bytes
    cpus = [g.cpu_percent_mean for g in summary.groups if g.cpu_percent_mean is not None]
    if rss is None or not cpus:
        return Check("footprint", False, "peak RSS or CPU use not measured")
    cpu = max(cpus)
    passed = rss <= MAX_PEAK_RSS_BYTES and cpu <= MAX_CPU_PERCENT
    return Check("footprint", passed,
                 f"peak RSS {rss / 1e6:.0f} MB (limit {MAX_PEAK_RSS_BYTES / 1e6:.0f} MB), "
                 f"mean CPU {cpu:.0f} % (limit {MAX_CPU_PERCENT:.0f} %)")


def judge(summary: EngineSummary) -> Verdict:
    """Run the four checks on one engine configuration."""
    checks = (check_fidelity(summary), check_loss(summary), check_speed(summary),
              check_footprint(summary))
    return Verdict(summary.label, checks)


def judge_all(summaries: list[EngineSummary]) -> list[Verdict]:
    """A verdict per engine configuration, in the summaries' order."""
    return [judge(s) for s in summaries]
