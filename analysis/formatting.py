"""Number formatting shared by the report, the verdicts and the plot titles."""

from __future__ import annotations

MISSING = "–"
P_FLOOR = 0.001


def fmt(value: float | int | None, digits: int = 3) -> str:
    """A number to ``digits`` significant figures, or a dash when missing."""
    return MISSING if value is None else f"{value:.{digits}g}"


def fmt_p(value: float | None) -> str:
    """A p-value as a cell: three decimals, '< 0.001', or a dash."""
    if value is None:
        return MISSING
    return f"< {P_FLOOR}" if value < P_FLOOR else f"{value:.3f}"


def p_equals(value: float | None) -> str:
    """A p-value inside a sentence: 'p = 0.243' or 'p < 0.001'."""
    text = fmt_p(value)
    return f"p {text}" if text.startswith("<") else f"p = {text}"


def balls_text(count: int | None) -> str:
    """'1 ball', '25 balls'; None means every ball count together."""
    if count is None:
        return "all ball counts"
    return f"{count} ball" if count == 1 else f"{count} balls"
