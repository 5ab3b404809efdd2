"""The paper's Table 2 rows as the paper's, beside the engines that run those simulators
here (ODE set up as Webots does, DART as Gazebo does; Bullet under CoppeliaSim 4.3 is 2.78,
PyBullet 3.x: close in kind only), with a line per simulator on what agrees and what not.

The paper's χ² is of its own mesh board with an unstated ball count and combination of
repetitions; its RTF ran against a real-time target, ours as fast as possible. So the lines
compare verdicts (χ² against its critical 19.68, balls lost or not, real time kept or not),
never the numbers themselves.
"""

from __future__ import annotations

from collections.abc import Mapping

from galton.analysis.card_intervals import Measure, measure_text
from galton.analysis.published import PAPER_CRITICAL_VALUE, PUBLISHED_TABLE2, PublishedRow

# the paper's simulator -> (the engine here, how close it stands)
STAND_INS: dict[str, tuple[str, str]] = {
    "Webots": ("ode", "ODE set up as Webots R2023b does (Webots runs its own ODE fork)"),
    "CoppeliaSim 4.3.0": ("pybullet", "Bullet 3.x (CoppeliaSim 4.3 runs Bullet 2.78): close "
                                      "in kind, not in version"),
    "Gazebo Harmonic": ("dart", "DART as gz-physics sets it up (ODE's collision detector)"),
}
LOST_FEW = 1.0  # % of balls: "almost none lost"


def _side(value: float) -> str:
    return "above" if value > PAPER_CRITICAL_VALUE else "below"


def chi2_line(row: PublishedRow, engine: str, chi2: Measure | None) -> str:
    if chi2 is None:
        return f"χ²: {engine} not measured"
    theirs, ours = _side(row.chi2), _side(chi2.value)
    straddles = chi2.low <= PAPER_CRITICAL_VALUE < chi2.high
    verdict = ("agrees" if theirs == ours and not straddles else
               "undecided (our interval straddles it)" if straddles else "does not agree")
    return (f"χ² {verdict}: {engine}'s median {measure_text(chi2)} is {ours} the critical "
            f"{PAPER_CRITICAL_VALUE:g}, {row.simulator}'s {row.chi2:g} {theirs} it")


def lost_line(row: PublishedRow, engine: str, lost: Measure | None) -> str:
    if lost is None:
        return f"balls lost: {engine} not measured"
    theirs, ours = row.lost_percent <= LOST_FEW, lost.value <= LOST_FEW
    verdict = "agrees" if theirs == ours else "does not agree"
    def said(few: bool) -> str:
        return f"almost none, ≤ {LOST_FEW:g} %" if few else "many"
    return (f"balls lost {verdict}: {row.simulator} lost {row.lost_percent:g} % "
            f"({said(theirs)}), {engine} {measure_text(lost, '%')} ({said(ours)})")


def _paper_kept(row: PublishedRow) -> bool | None:
    """Whether the paper's simulator kept real time (None: on one computer only)."""
    if row.rtf_high is not None and row.rtf_high < 1.0:
        return False
    if row.rtf_low is not None and row.rtf_low >= 1.0:
        return True
    return None


def rtf_line(row: PublishedRow, engine: str, rtf: Measure | None) -> str:
    if rtf is None:
        return f"real time: {engine} not measured"
    ours, theirs = rtf.value >= 1.0, _paper_kept(row)
    if theirs is None:
        verdict = "not comparable (the paper's depends on the computer)"
    else:
        verdict = "agrees" if theirs == ours else "does not agree"
    kept = "keeps" if ours else "does not keep"
    return (f"real time {verdict}: {engine} {kept} real time at 100 balls "
            f"({measure_text(rtf, '×')} as fast as possible); {row.simulator}: {row.rtf_text}")


def paper_rows(engines: list[str], column: Mapping[str, Mapping[str, Measure | None]]
               ) -> tuple[list[list[str]], list[str]]:
    """The table (paper's row, then the stand-in's) and a line per simulator whose
    stand-in ran here. ``column``: criterion key -> engine -> measure."""
    rows = [["simulator (paper)", "engine here", "χ² (paper)", "median χ² here",
             "lost (paper)", "lost here", "RTF (paper, real-time target)",
             "RTF at 100 balls here (as fast as possible)"]]
    lines = []
    for row in PUBLISHED_TABLE2:
        engine, how = STAND_INS[row.simulator]
        if engine not in engines:
            rows.append([row.simulator, f"{engine}: not on this card", f"{row.chi2:g}", "–",
                         f"{row.lost_percent:g} %", "–", row.rtf_text, "–"])
            continue
        chi2 = column["board_chi2_median"].get(engine)
        lost = column["board_lost_percent"].get(engine)
        rtf = column["rtf_100"].get(engine)
        rows.append([row.simulator, f"{engine}: {how}", f"{row.chi2:g}", measure_text(chi2),
                     f"{row.lost_percent:g} %", measure_text(lost, "%"), row.rtf_text,
                     measure_text(rtf, "×")])
        lines.append(f"**{row.simulator} / {engine}**: " + "; ".join(
            (chi2_line(row, engine, chi2), lost_line(row, engine, lost),
             rtf_line(row, engine, rtf))) + ".")
    return rows, lines
