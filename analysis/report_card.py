"""One report card across engines: each engine's measures with their 95 % intervals, the
law checks and Galton trials they came from, ranked per criterion (ties where intervals
overlap or gaps are under a threshold), and a recommendation per use, or "no clear
winner" and why (``card_rules``).

The client (``galton.client.report_card``) takes the measures; this module only holds,
judges and saves them, so a saved card.json rebuilds the same report
(``card_text`` writes it, ``report_card_outputs`` its files).
"""

from __future__ import annotations

import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.analysis.card_intervals import (
    BoardTrial,
    Measure,
    chi2_median,
    laws_measure,
    order_probability,
    resampled_w,
)
from galton.analysis.card_rules import Decision, Rules, Table, decide, gap_text, ranks
from galton.analysis.errors import RecordError
from galton.analysis.laws import Check

CARD_FORMAT = 2  # 2: every measure {value, low, high, n}; laws and board trials kept
BOARDS = {"board": "paper", "mesh": "paper-mesh"}  # measure prefix -> board preset


@dataclass
class CardResults:
    """Each engine's measures (criterion key -> Measure, None where not measured), its law
    checks and Galton trials, the RTF-versus-balls curve, and how and where they were
    taken."""

    measures: dict[str, dict[str, Measure | None]]
    laws: dict[str, list[Check]] = field(default_factory=dict)
    trials: dict[str, dict[str, list[BoardTrial]]] = field(default_factory=dict)
    curves: dict[str, dict[int, float]] = field(default_factory=dict)
    versions: dict[str, str] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)

    @property
    def engines(self) -> list[str]:
        return list(self.measures)

    def to_dict(self, rules: Rules | None = None) -> dict[str, Any]:
        """The measured record, and with ``rules`` what they make of it (criteria with
        their ranks, uses with their recommendation)."""
        body: dict[str, Any] = {
            "format": CARD_FORMAT,
            "measures": {e: {k: None if m is None else m.to_dict() for k, m in ms.items()}
                         for e, ms in self.measures.items()},
            "laws": {e: [c.to_dict() for c in checks] for e, checks in self.laws.items()},
            "trials": {e: {b: [t.to_dict() for t in ts] for b, ts in boards.items()}
                       for e, boards in self.trials.items()},
            "curves": {e: {str(n): r for n, r in c.items()} for e, c in self.curves.items()},
            "versions": self.versions, "config": self.config}
        if rules is not None:
            body |= judged(self, rules)
        return body

    @classmethod
    def from_dict(cls, body: dict[str, Any]) -> CardResults:
        if not isinstance(body, dict) or body.get("format") != CARD_FORMAT:
            raise RecordError(f"not a report card of format {CARD_FORMAT} (a card taken "
                              "before intervals is format 1: take it again)")
        try:
            return cls(
                measures={e: {k: None if m is None else Measure.from_dict(m)
                              for k, m in ms.items()} for e, ms in body["measures"].items()},
                laws={e: [Check.from_dict(c) for c in cs]
                      for e, cs in body.get("laws", {}).items()},
                trials={e: {b: [BoardTrial.from_dict(t) for t in ts] for b, ts in bs.items()}
                        for e, bs in body.get("trials", {}).items()},
                curves={e: {int(n): float(r) for n, r in c.items()}
                        for e, c in body.get("curves", {}).items()},
                versions=dict(body.get("versions", {})), config=dict(body.get("config", {})))
        except (AttributeError, KeyError, TypeError, ValueError) as error:
            raise RecordError(f"a report card's card.json is malformed ({error!r})") from error

    def save(self, path: Path, rules: Rules | None = None) -> None:
        path.write_text(json.dumps(self.to_dict(rules), indent=1) + "\n")


def criterion_table(card: CardResults, rules: Rules) -> Table:
    """Every criterion's measure per engine; a law criterion's counted from the checks."""
    table: dict[str, dict[str, Measure | None]] = {}
    for key, spec in rules.criteria.items():
        if spec.laws:
            table[key] = {e: _law_measure(card.laws.get(e, []), spec.laws)
                          for e in card.engines}
        else:
            table[key] = {e: card.measures[e].get(key) for e in card.engines}
    return table


def _law_measure(checks: list[Check], laws: tuple[str, ...]) -> Measure | None:
    chosen = [c for c in checks if c.law in laws]
    return laws_measure(chosen) if chosen else None


def decisions(card: CardResults, rules: Rules) -> dict[str, Decision]:
    table = criterion_table(card, rules)
    return {use: decide(rules, use, table, card.engines) for use in rules.uses}


def fidelity_orders(card: CardResults, rules: Rules, key: str) -> list[tuple[str, str, float]]:
    """For a Galton criterion, each engine and the next in its order, with the share of
    bootstrap resamples (of each engine's trials) in which that order holds."""
    prefix, _, statistic_name = key.partition("_")
    statistic = {"chi2_median": chi2_median, "effect_w": resampled_w}.get(statistic_name)
    board = BOARDS.get(prefix)
    spec = rules.criteria.get(key)
    if statistic is None or board is None or spec is None:
        return []
    column = criterion_table(card, rules)[key]
    values = {e: m.value for e, m in column.items() if m is not None}
    measured = sorted(values, key=values.__getitem__, reverse=not spec.lower_is_better)
    pairs = []
    for ahead, behind in itertools.pairwise(measured):
        a = [t for t in card.trials.get(ahead, {}).get(board, []) if t.settled]
        b = [t for t in card.trials.get(behind, {}).get(board, []) if t.settled]
        if a and b:
            pairs.append((ahead, behind, order_probability(
                a, b, statistic, spec.lower_is_better, int(card.config.get("seed", 0)))))
    return pairs


def _decision_body(card: CardResults, rules: Rules, table: Table,
                   decision: Decision) -> dict[str, Any]:
    use = rules.uses[decision.use]
    chosen = decision.engine or ""

    def entry(key: str, winner: str, loser: str | None) -> dict[str, Any]:
        mine, theirs = table[key].get(winner), table[key].get(loser or "")
        return {"criterion": key, "weight": use.weights[key], "engine": winner,
                "value": mine.to_dict() if mine else None, "rival": loser,
                "rival_value": theirs.to_dict() if theirs else None,
                "gap": gap_text(rules.criteria[key], mine, theirs) if mine and theirs else ""}
    return {"title": use.title, "engine": decision.engine, "margin": decision.margin,
            "rival": decision.rival,
            "decisive": [entry(k, chosen, decision.rival) for k in decision.decisive]
            if decision.engine else [],
            "why": decision.why,
            "weights": use.weights,
            "criteria": {k: {"weight": w, "ranks": ranks(rules.criteria[k], table[k])}
                         for k, w in use.weights.items()}}


def judged(card: CardResults, rules: Rules) -> dict[str, Any]:
    """card.json's derived part: per criterion its measures and ranks, per use its
    recommendation (engine or null, margin, decisive criteria) and its criteria's ranks."""
    table = criterion_table(card, rules)
    criteria: dict[str, dict[str, Any]] = {key: {"title": spec.title, "unit": spec.unit,
        "better": "lower" if spec.lower_is_better else "higher",
        "threshold": spec.threshold, "relative": spec.relative, "laws": list(spec.laws),
        "measures": {e: m.to_dict() if m else None for e, m in table[key].items()},
        "ranks": ranks(spec, table[key])} for key, spec in rules.criteria.items()}
    for key in ("board_effect_w", "board_chi2_median"):
        if key in criteria:
            criteria[key]["order_probability"] = [
                {"ahead": a, "behind": b, "probability": p}
                for a, b, p in fidelity_orders(card, rules, key)]
    return {"rules": {"source": rules.source, "min_margin": rules.min_margin},
            "criteria": criteria,
            "uses": {use: _decision_body(card, rules, table, d)
                     for use, d in decisions(card, rules).items()}}
