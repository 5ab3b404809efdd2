"""``galton-client report-card``: every engine measured on fidelity (the Galton board, the
physical laws), cost (RTF, footprint) and what embedding it costs, ranked per criterion,
with a recommendation per use (``galton.analysis.report_card``)."""

from __future__ import annotations

from galton.client.report_card.run import CardPlan, run_card, write_report_card

__all__ = ["CardPlan", "run_card", "write_report_card"]
