"""The report card's files: card.json (measures with intervals, and what the rules make of
them), report-card.md, the RTF-versus-balls plot, and a self-contained report-card.html
(its plots inlined as data URIs). Both texts come from the same blocks (``card_text``),
written whole: no line is wrapped or cut, whatever its width.
"""

from __future__ import annotations

import base64
import html
import re
from pathlib import Path

from galton.analysis.card_blocks import Block, Grid, Heading, Items, Para, markdown
from galton.analysis.card_rules import Rules, load_rules
from galton.analysis.card_text import TITLE, card_blocks
from galton.analysis.report_card import CardResults

CARD_JSON = "card.json"
CARD_MD = "report-card.md"
CARD_HTML = "report-card.html"
CURVE_PNG = "rtf_vs_balls.png"
_BOLD = re.compile(r"\*\*(.+?)\*\*")
_CODE = re.compile(r"`(.+?)`")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")


def render_card(card: CardResults, rules: Rules | None = None, plots: list[str] | None = None,
                law_links: list[str] | None = None) -> str:
    """report-card.md's text."""
    return markdown(TITLE, card_blocks(card, rules or load_rules(), plots, law_links))


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
    """Escape, then the Markdown marks the card uses: **bold**, `code` and [links](to)."""
    marked = _BOLD.sub(r"<strong>\1</strong>", html.escape(text, quote=False))
    marked = _CODE.sub(r"<code>\1</code>", marked)
    return _LINK.sub(r'<a href="\2">\1</a>', marked)


def _table(rows: list[list[str]]) -> str:
    head = "".join(f"<th>{_inline(c)}</th>" for c in rows[0])
    body = "".join("<tr>" + "".join(f"<td>{_inline(c)}</td>" for c in row) + "</tr>"
                   for row in rows[1:])
    return f"<table><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>"


def _image(path: Path) -> str:
    data = base64.b64encode(path.read_bytes()).decode("ascii")
    return f'<p><img alt="{html.escape(path.name)}" src="data:image/png;base64,{data}"></p>'


STYLE = ("body{font-family:sans-serif;max-width:80em;margin:2em auto;line-height:1.4}"
         "table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #bbb;"
         "padding:0.25em 0.5em;text-align:left}th{background:#eee}img{max-width:100%}")


def _html_block(block: Block, out: Path) -> str:
    if isinstance(block, Heading):
        return f"<h2>{html.escape(block.text)}</h2>"
    if isinstance(block, Para):
        return f"<p>{_inline(block.text)}</p>"
    if isinstance(block, Items):
        return "<ul>" + "".join(f"<li>{_inline(line)}</li>" for line in block.lines) + "</ul>"
    if isinstance(block, Grid):
        return _table(block.rows)
    return _image(out / block.path)


def render_html(card: CardResults, out: Path, rules: Rules | None = None,
                plots: list[str] | None = None, law_links: list[str] | None = None) -> str:
    """A page that needs no file beside it: the curve and the laws' plots inlined."""
    blocks = card_blocks(card, rules or load_rules(), plots, law_links)
    images = [p for p in law_links or [] if p.endswith(".png")]
    parts = ["<!DOCTYPE html><html><head><meta charset=\"utf-8\">",
             f"<title>{TITLE}</title>", f"<style>{STYLE}</style></head><body>",
             f"<h1>{TITLE}</h1>", *[_html_block(b, out) for b in blocks],
             *[_image(out / p) for p in images if (out / p).exists()], "</body></html>"]
    return "\n".join(parts) + "\n"


def write_card_outputs(card: CardResults, out: Path, rules: Rules | None = None,
                       plots: bool = True, law_links: list[str] | None = None
                       ) -> dict[str, Path]:
    """card.json, report-card.md, report-card.html and the plots in ``out`` (created);
    ``law_links`` (paths under ``out``: the laws' report and plots) are linked, and the
    plots among them inlined in the HTML."""
    chosen = rules or load_rules()
    out.mkdir(parents=True, exist_ok=True)
    card.save(out / CARD_JSON, chosen)
    drawn = plot_curve(card, out) if plots else []
    (out / CARD_MD).write_text(render_card(card, chosen, drawn, law_links))
    (out / CARD_HTML).write_text(render_html(card, out, chosen, drawn, law_links))
    return {"card_json": out / CARD_JSON, "card_md": out / CARD_MD,
            "card_html": out / CARD_HTML, **{p: out / p for p in drawn}}
