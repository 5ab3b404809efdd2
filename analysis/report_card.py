"""One report card across engines: the measures of each engine, ranked per criterion,
the paper's published rows beside them where it measured the same thing, and a plain
recommendation per use with its reasons.

The client (``galton.client.report_card``) takes the measures; this module only ranks and
writes them, so a saved card.json rebuilds the same report.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from galton.analysis.errors import RecordError
from galton.analysis.published import PUBLISHED_TABLE2

CARD_FORMAT = 1


@dataclass(frozen=True)
class Criterion:
    """A measure every engine has, and which way is better."""

    key: str
    title: str
    unit: str
    lower_is_better: bool
    paper: str = ""  # the paper's published values for the same measure, if any


CRITERIA: tuple[Criterion, ...] = (
    Criterion("laws_passed", "physical laws passed (of the suite's checks)", "checks", False),
    Criterion("board_chi2_median", "Galton board: median χ² per trial (paper board, "
              "primitives)", "", True,
              "; ".join(f"{r.simulator} {r.chi2:g}" for r in PUBLISHED_TABLE2)),
    Criterion("board_pooled_p", "Galton board: pooled Monte Carlo p", "", False),
    Criterion("board_lost_percent", "Galton board: balls lost", "%", True,
              "; ".join(f"{r.simulator} {r.lost_percent:g} %" for r in PUBLISHED_TABLE2)),
    Criterion("mesh_chi2_median", "Galton board as meshes: median χ² per trial (paper-mesh)",
              "", True),
    Criterion("mesh_lost_percent", "Galton board as meshes: balls lost", "%", True),
    Criterion("rtf_100", "real-time factor at 100 balls (as fast as possible)", "×", False,
              "; ".join(f"{r.simulator} {r.rtf_text}" for r in PUBLISHED_TABLE2)),
    Criterion("idle_rss_mb", "idle memory (RSS, board loaded)", "MB", True),
    Criterion("idle_cpu_percent", "idle CPU (board loaded, paused)", "% of a core", True),
    Criterion("rtf1_cpu_percent", "CPU at RTF 1 (board and 100 balls)", "% of a core", True),
    Criterion("status_zenoh_ms", "status round trip over Zenoh (p50)", "ms", True),
    Criterion("step_zenoh_ms", "step(1) round trip over Zenoh (p50)", "ms", True),
    Criterion("status_zmq_ms", "status round trip over ZeroMQ ipc (p50)", "ms", True),
    Criterion("step_zmq_ms", "step(1) round trip over ZeroMQ ipc (p50)", "ms", True),
    Criterion("snapshot_ms", "snapshot (p50)", "ms", True),
    Criterion("restore_ms", "restore (p50)", "ms", True),
    Criterion("fork_ms", "fork a world (p50)", "ms", True),
    Criterion("predict_ms", "predict 1 s ahead (p50)", "ms", True),
    Criterion("physics_errors", "physics errors (failed law runs and trials)", "", True),
)
BY_KEY = {c.key: c for c in CRITERIA}

USES: dict[str, tuple[str, ...]] = {
    "embedded predictor on a 2-core board computer": (
        "idle_rss_mb", "idle_cpu_percent", "rtf1_cpu_percent", "step_zmq_ms", "predict_ms",
        "fork_ms", "snapshot_ms", "restore_ms", "rtf_100", "physics_errors"),
    "faithful offline benchmark": (
        "laws_passed", "board_chi2_median", "board_pooled_p", "board_lost_percent",
        "physics_errors"),
}


RULE = ("For each use, the engine with the lowest sum of its ranks over the criteria that "
        "use cares about, every criterion weighing the same.")


@dataclass
class CardResults:
    """Each engine's measures (criterion key -> value, None where not measured), the
    RTF-versus-balls curve, and how and where they were taken."""

    measures: dict[str, dict[str, float | None]]
    curves: dict[str, dict[int, float]] = field(default_factory=dict)
    versions: dict[str, str] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)

    @property
    def engines(self) -> list[str]:
        return list(self.measures)

    def to_dict(self) -> dict[str, Any]:
        return {"format": CARD_FORMAT, "measures": self.measures,
                "curves": {e: {str(n): r for n, r in c.items()} for e, c in self.curves.items()},
                "versions": self.versions, "config": self.config}

    @classmethod
    def from_dict(cls, body: dict[str, Any]) -> CardResults:
        if not isinstance(body, dict) or body.get("format") != CARD_FORMAT:
            raise RecordError(f"not a report card of format {CARD_FORMAT}")
        return cls(measures={e: dict(m) for e, m in body["measures"].items()},
                   curves={e: {int(n): float(r) for n, r in c.items()}
                           for e, c in body.get("curves", {}).items()},
                   versions=dict(body.get("versions", {})), config=dict(body.get("config", {})))

    def save(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n")


def ranking(card: CardResults, key: str) -> list[str]:
    """Engines best first on one criterion; engines without the measure come last."""
    criterion = BY_KEY[key]
    measured = [e for e in card.engines if card.measures[e].get(key) is not None]
    unmeasured = [e for e in card.engines if e not in measured]
    ordered = sorted(measured, key=lambda e: float(card.measures[e][key] or 0.0),
                     reverse=not criterion.lower_is_better)
    return ordered + unmeasured


def rank_of(card: CardResults, key: str, engine: str) -> int:
    """1 for the best; engines with equal values share the better rank."""
    value = card.measures[engine].get(key)
    if value is None:
        return len(card.engines)
    order = ranking(card, key)
    return 1 + next(i for i, e in enumerate(order) if card.measures[e].get(key) == value)


@dataclass(frozen=True)
class Recommendation:
    use: str
    engine: str
    wins: list[str]  # criteria the engine ranks first on
    losses: list[str]  # criteria where another engine does better


def recommend(card: CardResults, use: str) -> Recommendation:
    """The engine with the lowest rank sum over the use's criteria (the first in the
    engine list on a tie), and where it leads and trails."""
    keys = [k for k in USES[use] if any(card.measures[e].get(k) is not None
                                        for e in card.engines)]
    totals = {e: sum(rank_of(card, k, e) for k in keys) for e in card.engines}
    best = min(card.engines, key=lambda e: totals[e])
    wins = [k for k in keys if rank_of(card, k, best) == 1]
    return Recommendation(use, best, wins, [k for k in keys if k not in wins])


def value_text(value: float | None, unit: str = "") -> str:
    if value is None:
        return "not measured"
    text = f"{value:.4g}" if abs(value) < 1e5 else f"{value:.3e}"
    return f"{text} {unit}".strip() if unit and unit not in ("checks",) else text


def _reason(card: CardResults, key: str, engine: str) -> str:
    criterion = BY_KEY[key]
    others = ", ".join(f"{e} {value_text(card.measures[e].get(key), criterion.unit)}"
                       for e in card.engines if e != engine)
    mine = value_text(card.measures[engine].get(key), criterion.unit)
    return f"{criterion.title}: {mine} (vs {others})" if others else f"{criterion.title}: {mine}"


def recommendation_lines(card: CardResults) -> list[str]:
    lines = []
    for use in USES:
        chosen = recommend(card, use)
        lines.append(f"- **{use}: {chosen.engine}.** It leads on "
                     + ("; ".join(_reason(card, k, chosen.engine) for k in chosen.wins)
                        or "nothing alone") + ".")
        if chosen.losses:
            lines.append("  It trails or ties on "
                         + "; ".join(_reason(card, k, chosen.engine) for k in chosen.losses)
                         + ".")
    return lines


def criteria_table(card: CardResults) -> list[list[str]]:
    """Header and rows: criterion, each engine's value with its rank, the paper's values."""
    header = ["criterion", *[f"{e} {card.versions.get(e, '')}".strip() for e in card.engines],
              "best", "published (paper)"]
    rows = [header]
    for criterion in CRITERIA:
        values = [f"{value_text(card.measures[e].get(criterion.key), criterion.unit)} "
                  f"(#{rank_of(card, criterion.key, e)})" for e in card.engines]
        leaders = [e for e in card.engines if card.measures[e].get(criterion.key) is not None
                   and rank_of(card, criterion.key, e) == 1]
        rows.append([criterion.title, *values, ", ".join(leaders) or "–",
                     criterion.paper or "–"])
    return rows


def curve_table(card: CardResults) -> list[list[str]]:
    counts = sorted({n for c in card.curves.values() for n in c})
    rows = [["balls", *card.engines]]
    for n in counts:
        rows.append([str(n), *[value_text(card.curves.get(e, {}).get(n))
                               for e in card.engines]])
    return rows


def markdown_table(rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(rows[0]) + " |", "| " + " | ".join("---" for _ in rows[0]) + " |"]
    lines += ["| " + " | ".join(r) + " |" for r in rows[1:]]
    return "\n".join(lines)


def about_lines(card: CardResults) -> list[str]:
    config = card.config
    host = config.get("host", {})
    return [f"- mode: {'quick' if config.get('quick') else 'full'}; board: "
            f"{config.get('board_plan', '')}; taken {config.get('taken', '')}",
            f"- machine: {host.get('cpu_model', 'unknown CPU')}, "
            f"{host.get('logical_cores', '?')} logical cores, "
            f"{int(host.get('memory_bytes', 0)) / 2**30:.0f} GiB, {host.get('os', '')}; "
            f"{config.get('machine_note', '')}",
            f"- command: `{config.get('command', 'galton-client report-card')}`",
            *([f"- the Galton trials ran on a pool of {len(config['pool'])} daemons: "
               f"{', '.join(config['pool'])}"] if config.get("pool") else []),
            *ray_lines(config.get("executor") or {}),
            "- the Galton board is built from primitives (paper) and, as the paper imported "
            "it, from triangle meshes (paper-mesh; not measured on engines without meshes)"]


def ray_lines(executor: dict[str, Any]) -> list[str]:
    """Where the Galton trials ran when on Ray, and the trials it retried."""
    if executor.get("kind") != "ray":
        return []
    retried = [f"{r['engine']} {r['balls']} balls rep {r['repetition'] + 1}"
               for r in executor.get("retried", [])]
    return [f"- the Galton trials ran on Ray ({executor.get('address')}): "
            f"{executor.get('actors')} actors on {executor.get('nodes')} node(s); retried: "
            f"{', '.join(retried) or 'none'}"]


def render_card(card: CardResults, plots: list[str] | None = None) -> str:
    lines = ["# Report card: choosing a simulator", "", *about_lines(card), "",
             "## Recommendation", "", RULE, "", *recommendation_lines(card), "",
             "## Per criterion", "",
             "Each value with its rank among the engines here (#1 best); the paper's "
             "published Webots, CoppeliaSim and Gazebo rows where it measured the same "
             "thing (its own machines, its own board as a mesh).", "",
             markdown_table(criteria_table(card)), "",
             "## Real-time factor versus balls", "", markdown_table(curve_table(card))]
    notes = card.config.get("notes") or []
    if notes:
        lines += ["", "## Physics errors met", "", *[f"- {n}" for n in notes]]
    if plots:
        lines += ["", *[f"![{p}]({p})" for p in plots]]
    return "\n".join(lines) + "\n"
