"""The report card's judgement: its criteria and uses (``card_uses.toml``, or a user's
``--weights FILE`` over it), when one engine is clearly better than another on a
criterion, the ranks that follow, and the recommendation per use.

Clearly better: its value is better, the two 95 % intervals do not overlap, and the gap is
at least the criterion's practical threshold. Anything less is a tie, so noise gives ties,
not leads. An engine is recommended for a use when, against every other engine, the weight
of the criteria where it is clearly better less the weight of those where it is clearly
worse is at least ``min_margin`` of the use's weight (counting the criteria both have);
otherwise the card says "no clear winner", and why.
"""

from __future__ import annotations

import difflib
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from importlib.resources import files
from pathlib import Path
from typing import Any

from galton.analysis.card_intervals import Measure
from galton.analysis.errors import WeightsError

SHIPPED = "card_uses.toml"
# criterion -> engine -> its measure (None: not measured on that engine)
Table = Mapping[str, Mapping[str, Measure | None]]


@dataclass(frozen=True)
class CriterionSpec:
    """A measure every engine has, which way is better, and the gap that matters."""

    key: str
    title: str
    unit: str
    lower_is_better: bool
    threshold: float
    relative: bool = False
    laws: tuple[str, ...] = ()  # a law criterion: the checks of these laws passed
    why: str = ""

    def threshold_text(self) -> str:
        if self.relative:
            return percent(self.threshold)
        unit = "" if self.unit in ("", "checks") else f" {self.unit}"
        return f"{self.threshold:g}{unit}"


@dataclass(frozen=True)
class UseSpec:
    key: str
    title: str
    about: str
    weights: dict[str, float]


@dataclass(frozen=True)
class Rules:
    criteria: dict[str, CriterionSpec]
    uses: dict[str, UseSpec]
    min_margin: float
    source: str = SHIPPED


def percent(share: float) -> str:
    """``15 %``: a share written as the card writes percentages."""
    return f"{100 * share:.0f} %"


def _fail(where: str, what: str) -> WeightsError:
    return WeightsError(f"{where}: {what}")


def _known(key: str, known: Mapping[str, object], where: str) -> None:
    if key not in known:
        near = difflib.get_close_matches(key, list(known), 1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise _fail(where, f"unknown criterion {key!r}{hint}; known: {', '.join(known)}")


_FIELDS = {"title", "unit", "better", "threshold", "relative", "laws", "why"}


def _criterion(key: str, body: Any, base: CriterionSpec | None, where: str) -> CriterionSpec:
    if not isinstance(body, dict):
        raise _fail(where, f"criteria.{key} must be a table")
    unknown = set(body) - _FIELDS
    if unknown:
        raise _fail(where, f"criteria.{key}: unknown field(s) {sorted(unknown)}; "
                    f"a criterion has {sorted(_FIELDS)}")
    if base is None and not body.get("laws"):
        raise _fail(where, f"criteria.{key} is not measured by the card; a new criterion "
                    "must be a law criterion (give it `laws`)")
    try:
        better = body.get("better", None if base is None else
                          ("lower" if base.lower_is_better else "higher"))
        if better not in ("lower", "higher"):
            raise ValueError(f"better must be 'lower' or 'higher', got {better!r}")
        threshold = float(body.get("threshold", 0.0 if base is None else base.threshold))
        if threshold < 0:
            raise ValueError(f"threshold must be >= 0, got {threshold}")
        spec = CriterionSpec(
            key, str(body.get("title", key if base is None else base.title)),
            str(body.get("unit", "" if base is None else base.unit)), better == "lower",
            threshold, bool(body.get("relative", False if base is None else base.relative)),
            tuple(str(k) for k in body.get("laws", () if base is None else base.laws)),
            str(body.get("why", "" if base is None else base.why)))
    except (TypeError, ValueError) as error:
        raise _fail(where, f"criteria.{key}: {error}") from error
    return spec


def _use(key: str, body: Any, criteria: Mapping[str, CriterionSpec], where: str) -> UseSpec:
    if not isinstance(body, dict) or not isinstance(body.get("weights"), dict):
        raise _fail(where, f"uses.{key} must be a table with a `weights` table")
    weights: dict[str, float] = {}
    for name, weight in body["weights"].items():
        _known(name, criteria, f"{where}: uses.{key}.weights")
        if not isinstance(weight, int | float) or weight < 0:
            raise _fail(where, f"uses.{key}.weights.{name} must be a number >= 0, "
                        f"got {weight!r}")
        if weight > 0:
            weights[name] = float(weight)
    if not weights:
        raise _fail(where, f"uses.{key} weighs no criterion")
    return UseSpec(key, str(body.get("title", key)), str(body.get("about", "")), weights)


def _read(path: Path) -> dict[str, Any]:
    try:
        return tomllib.loads(path.read_text())
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as error:
        raise WeightsError(f"cannot read the card's weights {path}: {error}") from error


def _apply(body: dict[str, Any], rules: Rules | None, where: str) -> Rules:
    unknown = set(body) - {"decision", "criteria", "uses"}
    if unknown:
        raise _fail(where, f"unknown table(s) {sorted(unknown)}; expected decision, "
                    "criteria, uses")
    criteria = dict(rules.criteria) if rules else {}
    for key, entry in body.get("criteria", {}).items():
        criteria[key] = _criterion(key, entry, criteria.get(key) if rules else
                                   CriterionSpec(key, key, "", True, 0.0), where)
    uses = ({k: _use(k, v, criteria, where) for k, v in body["uses"].items()}
            if "uses" in body else dict(rules.uses) if rules else {})
    margin = body.get("decision", {}).get("min_margin", rules.min_margin if rules else None)
    if not isinstance(margin, int | float) or not 0 < margin <= 1:
        raise _fail(where, f"decision.min_margin must be in (0, 1], got {margin!r}")
    if not uses:
        raise _fail(where, "no use is declared")
    return Rules(criteria, uses, float(margin), where)


def load_rules(path: Path | None = None) -> Rules:
    """The shipped criteria and uses, with the file at ``path`` read over them."""
    shipped = tomllib.loads(files("galton.analysis").joinpath(SHIPPED).read_text())
    rules = replace(_apply(shipped, None, SHIPPED), source=f"the shipped analysis/{SHIPPED}")
    return rules if path is None else replace(_apply(_read(path), rules, str(path)),
                                              source=str(path))


def gap(spec: CriterionSpec, a: Measure, b: Measure) -> float:
    """How far apart two values are, in the criterion's threshold's terms."""
    if not spec.relative:
        return abs(a.value - b.value)
    small, large = sorted((abs(a.value), abs(b.value)))
    if large == 0:
        return 0.0
    return float("inf") if small == 0 else large / small - 1


def gap_text(spec: CriterionSpec, a: Measure, b: Measure) -> str:
    """``2.7× lower`` or ``3.1 % of a core lower``: how much better ``a`` is."""
    side = "lower" if spec.lower_is_better else "higher"
    if spec.relative:
        return f"{gap(spec, a, b) + 1:.2g}× {side}"
    unit = "" if spec.unit == "" else f" {spec.unit}"
    return f"{abs(a.value - b.value):.3g}{unit} {side}"


def clearly_better(spec: CriterionSpec, a: Measure | None, b: Measure | None) -> bool:
    """``a`` better than ``b``, their intervals apart and the gap past the threshold."""
    if a is None or b is None or a.overlaps(b) or gap(spec, a, b) < spec.threshold:
        return False
    return a.value < b.value if spec.lower_is_better else a.value > b.value


def ranks(spec: CriterionSpec, measures: Mapping[str, Measure | None]) -> dict[str, int | None]:
    """1 + the number of engines clearly better; ties share a rank; None: not measured."""
    return {e: None if m is None else 1 + sum(clearly_better(spec, o, m)
                                                for o in measures.values())
            for e, m in measures.items()}


@dataclass(frozen=True)
class Decision:
    """A use's recommendation: the engine (None: no clear winner), its lead over its
    nearest rival as a share of the use's weight, and the criteria that decide it."""

    use: str
    engine: str | None
    margin: float
    rival: str | None
    decisive: list[str] = field(default_factory=list)  # where the engine beats the rival
    against: list[str] = field(default_factory=list)  # where the rival beats the engine
    why: str = ""


def _wins(use: UseSpec, criteria: Mapping[str, CriterionSpec], table: Table, a: str,
          b: str) -> list[str]:
    return [k for k in use.weights if clearly_better(criteria[k], table[k].get(a),
                                                     table[k].get(b))]


def lead(use: UseSpec, criteria: Mapping[str, CriterionSpec], table: Table, a: str,
         b: str) -> float:
    """(weight where ``a`` is clearly better − where ``b`` is) / weight both measured."""
    both = [k for k in use.weights if table[k].get(a) is not None
            and table[k].get(b) is not None]
    total = sum(use.weights[k] for k in both)
    if total == 0:
        return 0.0
    ahead = sum(use.weights[k] for k in _wins(use, criteria, table, a, b))
    behind = sum(use.weights[k] for k in _wins(use, criteria, table, b, a))
    return (ahead - behind) / total


def decide(rules: Rules, use_key: str, table: Table, engines: list[str]) -> Decision:
    """The engine that leads every other by ``min_margin``, or no clear winner."""
    use = rules.uses[use_key]
    if len(engines) < 2:
        return Decision(use_key, engines[0] if engines else None, 0.0, None,
                        why="one engine measured: nothing to compare")
    worst = {a: min((lead(use, rules.criteria, table, a, b), b) for b in engines
                     if b != a) for a in engines}
    best = max(engines, key=lambda e: worst[e][0])
    margin, rival = worst[best]
    decisive = _wins(use, rules.criteria, table, best, rival)
    against = _wins(use, rules.criteria, table, rival, best)
    if margin >= rules.min_margin:
        return Decision(use_key, best, margin, rival, decisive, against)
    return Decision(use_key, None, margin, rival, decisive, against,
                    why=_no_winner(rules, use, best, rival, margin, decisive, against))


def _no_winner(rules: Rules, use: UseSpec, best: str, rival: str, margin: float,
               decisive: list[str], against: list[str]) -> str:
    need = f"the {percent(rules.min_margin)} of the use's weight a recommendation needs"
    if not decisive and not against:
        return (f"{best} and {rival} tie on every criterion this use weighs (intervals "
                f"overlap or gaps under the thresholds)")
    def named(keys: list[str]) -> str:
        return ", ".join(f"{rules.criteria[k].title} (weight {use.weights[k]:g})"
                         for k in keys) or "nothing"
    return (f"{best} leads {rival} by {percent(margin)} of the weight, under {need}: {best} is "
            f"clearly better on {named(decisive)}; {rival} on {named(against)}; the rest tie")
