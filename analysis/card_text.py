"""What the report card says, as blocks (``card_blocks``): where and how it was taken, the
recommendation per use with its decisive criteria and margins (or "no clear winner" and
why), every criterion with each engine's interval and rank, the failed laws and which uses
they bear on, the paper's rows beside their stand-ins, and the RTF curve."""

from __future__ import annotations

from typing import Any

from galton.analysis.card_blocks import Block, Grid, Heading, Items, Para, Picture
from galton.analysis.card_intervals import NEAR_LINE, measure_text, number
from galton.analysis.card_paper import paper_rows
from galton.analysis.card_rules import (
    CriterionSpec,
    Decision,
    Rules,
    Table,
    gap_text,
    percent,
    ranks,
)
from galton.analysis.laws import Check
from galton.analysis.report_card import CardResults, criterion_table, decisions, fidelity_orders

TITLE = "Report card: choosing a simulator"
ALL_LAWS = "laws_passed"  # the criterion that counts every check of the suite


def rule_text(rules: Rules) -> str:
    return (f"An engine is recommended for a use when, against every other engine, the "
            f"weight of the criteria on which it is clearly better, less the weight of those "
            f"on which it is clearly worse, is at least {percent(rules.min_margin)} of the "
            f"weight both were measured on. Clearly better: its 95 % interval does not "
            f"overlap the other's and the gap is at least the criterion's threshold; "
            f"anything less is a tie. Criteria, thresholds and weights: `{rules.source}`.")


def about_lines(card: CardResults) -> list[str]:
    config = card.config
    host = config.get("host", {})
    return [f"mode: {'quick' if config.get('quick') else 'full'}; board: "
            f"{config.get('board_plan', '')}; seed {config.get('seed', 0)}; taken "
            f"{config.get('taken', '')}",
            f"machine: {host.get('cpu_model', 'unknown CPU')}, "
            f"{host.get('logical_cores', '?')} logical cores, "
            f"{int(host.get('memory_bytes', 0)) / 2**30:.0f} GiB, {host.get('os', '')}"
            + (f"; {config['machine_note']}" if config.get("machine_note") else ""),
            f"command: `{config.get('command', 'galton-client report-card')}`",
            *([f"the Galton trials ran on a pool of {len(config['pool'])} daemons: "
               f"{', '.join(config['pool'])}"] if config.get("pool") else []),
            *ray_lines(config.get("executor") or {}),
            "each figure is followed by its 95 % interval in brackets (docs/report-card/"
            "reading.md says how each is made); `(#2)` is a rank, shared on a tie"]


def ray_lines(executor: dict[str, Any]) -> list[str]:
    """Where the Galton trials ran when on Ray, and the trials it retried."""
    if executor.get("kind") != "ray":
        return []
    retried = [f"{r['engine']} {r['balls']} balls rep {r['repetition'] + 1}"
               for r in executor.get("retried", [])]
    return [f"the Galton trials ran on Ray ({executor.get('address')}): "
            f"{executor.get('actors')} actors on {executor.get('nodes')} node(s); retried: "
            f"{', '.join(retried) or 'none'}"]


def _versus(spec: CriterionSpec, table: Table, key: str, a: str, b: str) -> str:
    mine, theirs = table[key][a], table[key][b]
    if mine is None or theirs is None:
        return spec.title
    return (f"{spec.title}: {measure_text(mine, spec.unit)} vs "
            f"{measure_text(theirs, spec.unit)}, {gap_text(spec, mine, theirs)}")


def decision_line(rules: Rules, table: Table, decision: Decision,
                  bearing: dict[str, list[str]]) -> str:
    use = rules.uses[decision.use]
    weights = ", ".join(f"{rules.criteria[k].title.split(' (')[0]} {w:g}"
                        for k, w in use.weights.items())
    tail = f" Weights: {weights}."
    if bearing.get(decision.use):
        tail += " Failed laws that bear on it: " + "; ".join(bearing[decision.use]) + "."
    if decision.engine is None:
        return f"**{use.title}: no clear winner.** {decision.why}.{tail}"
    if decision.rival is None:
        return f"**{use.title}: {decision.engine}** ({decision.why}).{tail}"
    def listed(keys: list[str], a: str, b: str) -> str:
        return "; ".join(f"{_versus(rules.criteria[k], table, k, a, b)} (weight "
                         f"{use.weights[k]:g})" for k in keys)
    text = (f"**{use.title}: {decision.engine}**, ahead of its nearest rival "
            f"{decision.rival} by {percent(decision.margin)} of the weight. Decisive: "
            f"{listed(decision.decisive, decision.engine, decision.rival)}.")
    if decision.against:
        text += (f" Against it: "
                 f"{listed(decision.against, decision.rival, decision.engine)}.")
    return text + tail


def criteria_rows(card: CardResults, rules: Rules, table: Table) -> list[list[str]]:
    rows = [["criterion", *[f"{e} {card.versions.get(e, '')}".strip() for e in card.engines],
             "n", "tie under"]]
    for key, spec in rules.criteria.items():
        column = table[key]
        rank = ranks(spec, column)
        cells = [f"{measure_text(column[e], spec.unit)} (#{rank[e]})" if column[e] else
                 "not measured" for e in card.engines]
        counts = sorted({m.n for m in column.values() if m is not None})
        rows.append([spec.title, *cells, "/".join(map(str, counts)) or "–",
                     spec.threshold_text()])
    return rows


def order_lines(card: CardResults, rules: Rules) -> list[str]:
    lines = []
    for key in ("board_effect_w", "board_chi2_median"):
        for ahead, behind, p in fidelity_orders(card, rules, key):
            lines.append(f"{rules.criteria[key].title}: {ahead} stays ahead of {behind} in "
                         f"{percent(p)} of resamples of their trials")
    return lines


def bearing_uses(rules: Rules, law: str) -> list[str]:
    """The uses a failure of ``law`` bears on: those with a criterion naming that law, and
    those whose heaviest criteria include every law's count (the faithful benchmark); a
    use that counts every law only lightly is not named for each failure."""
    found = []
    for key, use in rules.uses.items():
        heaviest = max(use.weights.values())
        if any(law in rules.criteria[c].laws or (c == ALL_LAWS and w >= heaviest)
               for c, w in use.weights.items()):
            found.append(key)
    return found


def failed_checks(card: CardResults) -> list[tuple[str, Check]]:
    return [(e, c) for e in card.engines for c in card.laws.get(e, []) if not c.passed]


def failure_rows(card: CardResults, rules: Rules) -> list[list[str]]:
    rows = [["engine", "law", "quantity", "measured", "theory", "tolerance", "bears on"]]
    for engine, check in failed_checks(card):
        measured = ("did not run: " + check.note if check.value is None
                    else f"{number(check.value)} {check.unit}".removesuffix(" 1"))
        rows.append([engine, check.law, check.quantity, measured,
                     f"{number(check.theory)}", f"±{number(check.tolerance)}",
                     ", ".join(rules.uses[u].title for u in bearing_uses(rules, check.law))
                     or "no use weighs it"])
    return rows


def bearing_by_use(card: CardResults, rules: Rules) -> dict[str, list[str]]:
    """Per use, per engine: the failed laws that bear on it (``tower ×2``: two checks)."""
    found: dict[str, dict[str, dict[str, int]]] = {}
    for engine, check in failed_checks(card):
        for use in bearing_uses(rules, check.law):
            laws = found.setdefault(use, {}).setdefault(engine, {})
            laws[check.law] = laws.get(check.law, 0) + 1
    return {use: [f"{engine}: " + ", ".join(law + (f" ×{n}" if n > 1 else "")
                                            for law, n in laws.items())
                  for engine, laws in engines.items()] for use, engines in found.items()}


def failure_blocks(card: CardResults, rules: Rules, law_links: list[str]) -> list[Block]:
    links = ", ".join(f"[{p}]({p})" for p in law_links)
    blocks: list[Block] = [Heading("Failed laws"), Para(
        f"Every check an engine failed, with its value, theory and tolerance (a check "
        f"passes when |value − theory| ≤ tolerance; one within a factor {NEAR_LINE:g} of "
        f"its tolerance widens the count's interval). Bears on: the uses with a criterion "
        f"naming the law, and those that weigh the count of every law most. The laws' "
        f"report and plots: {links or 'laws/ (not written)'}.")]
    rows = failure_rows(card, rules)
    blocks.append(Grid(rows) if len(rows) > 1 else Para("Every engine passed every check."))
    return blocks


def curve_rows(card: CardResults) -> list[list[str]]:
    counts = sorted({n for c in card.curves.values() for n in c})
    rows = [["balls", *card.engines]]
    for n in counts:
        rows.append([str(n), *[number(card.curves[e][n]) if n in card.curves.get(e, {})
                               else "–" for e in card.engines]])
    return rows


def card_blocks(card: CardResults, rules: Rules, plots: list[str] | None = None,
                law_links: list[str] | None = None) -> list[Block]:
    table = criterion_table(card, rules)
    bearing = bearing_by_use(card, rules)
    paper, agreement = paper_rows(card.engines, table)
    blocks: list[Block] = [
        Items(about_lines(card)),
        Heading("Recommendation"), Para(rule_text(rules)),
        Items([decision_line(rules, table, d, bearing)
               for d in decisions(card, rules).values()]),
        Heading("Per criterion"),
        Para("Each engine's figure, its 95 % interval and its rank (#1 best; engines share "
             "a rank unless one is clearly better); n: the repetitions behind each figure "
             "(trials, samples or checks); tie under: the criterion's practical threshold."),
        Grid(criteria_rows(card, rules, table))]
    orders = order_lines(card, rules)
    if orders:
        blocks += [Para("How stable the Galton order is (bootstrap over each engine's "
                        "trials):"), Items(orders)]
    blocks += failure_blocks(card, rules, law_links or [])
    blocks += [Heading("Beside the paper's simulators"),
               Para("The paper's Table 2 rows, as the paper gives them, beside the engine "
                    "each simulator runs, here. Its χ² is of its own mesh board (ball count "
                    "and pooling unstated) and its RTF ran against a real-time target, so "
                    "the lines compare verdicts, not numbers."),
               Grid(paper), Items(agreement or ["none of the paper's engines ran here"])]
    blocks += [Heading("Real-time factor versus balls"),
               Para("Mean RTF of the trials at each ball count (one trial each but at the "
                    "fidelity count): indicative, no interval."),
               Grid(curve_rows(card)), *[Picture(p) for p in plots or []]]
    notes = card.config.get("notes") or []
    if notes:
        blocks += [Heading("Physics errors met"), Items(list(notes))]
    return blocks
