"""The law suite's report: a Markdown table like the paper's Table 2 (law, theory, each
engine's value and error, pass or fail), the tolerances and why, and plots of the series
the experiments kept (the pendulum's energy, the torque-free body's momentum and axis).

Rebuilt from ``LawResults`` alone: ``write_law_outputs`` is what ``galton-client laws``
calls, and a saved results.json gives the same report.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from galton.analysis.laws import Check, LawResults

RESULTS_JSON = "results.json"
REPORT_MD = "report.md"
PLOT_FILES = {  # plot file -> the series (by name prefix) it draws
    "pendulum_energy.png": "pendulum energy",
    "torque_free.png": "torque-free",
}


def number(value: float | None) -> str:
    """How the report writes a number: 6 significant digits (``—`` for none)."""
    if value is None:
        return "—"
    if not math.isfinite(value):
        return str(value)
    return f"{value:.6g}"


def cell(check: Check | None, theory: float | None = None) -> str:
    """One engine's cell: value, signed error, its tolerance (it may depend on the step),
    the verdict, and its own theory where it differs from the row's (another gravity)."""
    if check is None:
        return "not run"
    if check.value is None:
        return f"— ({check.note})" if check.note else "—"
    verdict = "**pass**" if check.passed else "**FAIL**"
    own = "" if theory is None or theory == check.theory else f", theory {number(check.theory)}"
    return (f"{number(check.value)} ({number(check.error)}) ±{number(check.tolerance)}{own} "
            f"{verdict}")


def _first(results: LawResults, law: str, quantity: str) -> Check:
    for record in results.engines:
        found = results.check(record.engine, law, quantity)
        if found is not None:
            return found
    raise KeyError((law, quantity))  # rows() only lists measured pairs


def law_table(results: LawResults) -> str:
    """The Table-2-like grid: a row per measured quantity, a column per engine."""
    engines = [r.engine for r in results.engines]
    lines = ["| law | quantity | unit | theory | "
             + " | ".join(f"{e}: value (error) ±tolerance" for e in engines) + " |",
             "| --- | --- | --- | --- | " + " | ".join("---" for _ in engines) + " |"]
    for law, quantity in results.rows():
        first = _first(results, law, quantity)
        cells = [cell(results.check(e, law, quantity), first.theory) for e in engines]
        lines.append(f"| {law} | {quantity} | {first.unit} | {number(first.theory)} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines)


def summary_lines(results: LawResults) -> list[str]:
    return [f"- **{r.engine}** {r.engine_version}: {r.passed} of {len(r.checks)} checks "
            f"pass (step {number(r.timestep)} s, g {number(r.gravity)} m/s², "
            f"{r.wall_s:.1f} s wall)" for r in results.engines]


def tolerance_lines(results: LawResults) -> list[str]:
    """Each tolerance's reason, once per (law, quantity)."""
    return [f"- {law}, {quantity}: {_first(results, law, quantity).why}"
            for law, quantity in results.rows()]


def render_law_report(results: LawResults, plots: list[str] | None = None) -> str:
    config = results.config
    lines = ["# Physical laws through the bridge", "",
             f"Engines: {', '.join(r.engine for r in results.engines)}; laws: "
             f"{', '.join(config.get('laws', []))}; seed {config.get('seed', 0)}; "
             f"parameters {json.dumps(config.get('params') or 'the defaults')}. Each "
             "value is measured through the daemon, each error is value − theory, and a "
             "check passes when |error| ≤ tolerance.", "", *summary_lines(results), "",
             law_table(results), "", "## Tolerances and why", "",
             *tolerance_lines(results)]
    if plots:
        lines += ["", "## Plots", "", *[f"![{p}]({p})" for p in plots]]
    return "\n".join(lines) + "\n"


def plot_series(results: LawResults, out: Path) -> list[str]:
    """One PNG per kind of series any engine kept; the file names written (none where
    matplotlib, the [bench] extra, is not installed: the report says so)."""
    try:
        from matplotlib.figure import Figure
    except ImportError:
        return []

    written = []
    for filename, prefix in PLOT_FILES.items():
        names = sorted({n for r in results.engines for n in r.series if n.startswith(prefix)})
        if not names:
            continue
        fig = Figure(figsize=(7.0, 2.6 * len(names)))
        axes = fig.subplots(len(names), 1, squeeze=False)[:, 0]
        for ax, name in zip(axes, names, strict=True):
            for record in results.engines:
                data = record.series.get(name)
                if data is not None:
                    ax.plot(data["t"], data["y"], label=record.engine, linewidth=1)
            ax.set_title(name)
            ax.set_xlabel("sim time (s)")
            ax.legend()
        fig.tight_layout()
        fig.savefig(out / filename, dpi=100)
        written.append(filename)
    return written


def write_law_outputs(results: LawResults, out_dir: Path, plots: bool = True
                      ) -> dict[str, Path]:
    """results.json, report.md and the plots in ``out_dir`` (created)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    results.save(out_dir / RESULTS_JSON)
    drawn = plot_series(results, out_dir) if plots else []
    (out_dir / REPORT_MD).write_text(render_law_report(results, drawn))
    return {"results_json": out_dir / RESULTS_JSON, "report_md": out_dir / REPORT_MD,
            **{name: out_dir / name for name in drawn}}
