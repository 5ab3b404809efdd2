"""The report card's files: card.json, report-card.md, the RTF-versus-balls plot, and a
self-contained report-card.html (its plots inlined as data URIs, no file beside it needed).
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from galton.analysis.report_card import (
    RULE,
    CardResults,
    about_lines,
    criteria_table,
    curve_table,
    recommendation_lines,
    render_card,
)

CARD_JSON = "card.json"
CARD_MD = "report-card.md"
CARD_HTML = "report-card.html"
CURVE_PNG = "rtf_vs_balls.png"
_BOLD = re.compile(r"\*\*(.+?)\*\*")
_CODE = re.compile(r"`(.+?)`")


def plot_curve(card: CardResults, out: Path) -> list[str]:
    """RTF against balls, log-log, one line per engine (nothing when no curve was run)."""
    if not any(card.curves.values()):
        return []
    from matplotlib.figure import Figure  # the [bench] extra, loaded only to draw

    fig = Figure(figsize=(6.0, 3.6))
    ax = fig.subplots()
    for engine, curve in card.curves.items():
        counts = sorted(curve)
        ax.plot(counts, [curve[n] for n in counts], "o-", label=engine)
    ax.axhline(1.0, color="grey", linewidth=0.8, linestyle="--", label="real time")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("balls")
    ax.set_ylabel("real-time factor")
    ax.set_title("Galton board, as fast as possible")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / CURVE_PNG, dpi=100)
    return [CURVE_PNG]


def _inline(text: str) -> str:
    """Escape, then the two Markdown marks the card uses: **bold** and `code`."""
    return _CODE.sub(r"<code>\1</code>", _BOLD.sub(r"<strong>\1</strong>", html.escape(text)))


def _table(rows: list[list[str]]) -> str:
    head = "".join(f"<th>{html.escape(c)}</th>" for c in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                   for row in rows[1:])
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _list(lines: list[str]) -> str:
    items = "".join(f"<li>{_inline(line.removeprefix('- ').strip())}</li>" for line in lines)
    return f"<ul>{items}</ul>"


def _image(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<p><img alt="{html.escape(path.name)}" src="data:image/png;base64,{data}"></p>'


STYLE = ("body{font-family:sans-serif;max-width:70em;margin:2em auto;line-height:1.4}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
         "padding:0.25em 0.5em;text-align:left}th{background:#eee}img{max-width:100%}")


def render_html(card: CardResults, images: list[Path]) -> str:
    parts = ["<!DOCTYPE html><html><head><meta charset=\"utf-8\">",
             "<title>Report card: choosing a simulator</title>",
             f"<style>{STYLE}</style></head><body>",
             "<h1>Report card: choosing a simulator</h1>", _list(about_lines(card)),
             "<h2>Recommendation</h2>", f"<p>{_inline(RULE)}</p>",
             _list(_joined(recommendation_lines(card))),
             "<h2>Per criterion</h2>", _table(criteria_table(card)),
             "<h2>Real-time factor versus balls</h2>", _table(curve_table(card)),
             *[_image(p) for p in images], *_notes(card), "</body></html>"]
    return "\n".join(parts) + "\n"


def _notes(card: CardResults) -> list[str]:
    notes = [f"- {n}" for n in card.config.get("notes") or []]
    return ["<h2>Physics errors met</h2>", _list(notes)] if notes else []


def _joined(lines: list[str]) -> list[str]:
    """Markdown list items with their indented continuation lines folded in."""
    items: list[str] = []
    for line in lines:
        if line.startswith("  ") and items:
            items[-1] += " " + line.strip()
        else:
            items.append(line)
    return items


def write_card_outputs(card: CardResults, out: Path, plots: bool = True,
                       extra_images: list[Path] | None = None) -> dict[str, Path]:
    """card.json, report-card.md, report-card.html and the plots in ``out`` (created);
    ``extra_images`` (the laws' plots) are inlined in the HTML too."""
    out.mkdir(parents=True, exist_ok=True)
    card.save(out / CARD_JSON)
    drawn = plot_curve(card, out) if plots else []
    (out / CARD_MD).write_text(render_card(card, drawn))
    images = [out / p for p in drawn] + list(extra_images or [])
    (out / CARD_HTML).write_text(render_html(card, images))
    return {"card_json": out / CARD_JSON, "card_md": out / CARD_MD,
            "card_html": out / CARD_HTML, **{p: out / p for p in drawn}}
