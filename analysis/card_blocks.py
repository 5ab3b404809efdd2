"""The pieces a report card is written in, shared by its Markdown and its HTML page so the
two always say the same: headings, paragraphs, lists, tables and pictures, with text in
the three Markdown marks the card uses (**bold**, `code`, [links](path))."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Heading:
    text: str


@dataclass(frozen=True)
class Para:
    text: str


@dataclass(frozen=True)
class Items:
    lines: list[str]


@dataclass(frozen=True)
class Grid:
    rows: list[list[str]]  # the first row is the header


@dataclass(frozen=True)
class Picture:
    path: str  # relative to the card


Block = Heading | Para | Items | Grid | Picture


def markdown_table(rows: list[list[str]]) -> str:
    """A whole Markdown table: never wrapped or cut, whatever its width."""
    def line(cells: list[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"
    return "\n".join([line(rows[0]), line(["---"] * len(rows[0])),
                      *(line(r) for r in rows[1:])])


def markdown(title: str, blocks: list[Block]) -> str:
    parts = [f"# {title}"]
    for block in blocks:
        if isinstance(block, Heading):
            parts.append(f"## {block.text}")
        elif isinstance(block, Para):
            parts.append(block.text)
        elif isinstance(block, Items):
            parts.append("\n".join(f"- {line}" for line in block.lines))
        elif isinstance(block, Grid):
            parts.append(markdown_table(block.rows))
        else:
            parts.append(f"![{block.path}]({block.path})")
    return "\n\n".join(parts) + "\n"
