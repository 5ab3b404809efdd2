"""Write the table of contents at the top of every long page (README and docs/, over
``LONG_PAGE`` lines), from its own headings, so that a reader can find a section.

Usage: python docs/make_contents.py   (rewrites the pages in place; run it after adding,
renaming or removing a heading). tests/protocol/test_docs_pages.py fails while a page's
contents are stale.

The contents sit between two HTML comments just after the page's first paragraph, list
every ``##`` heading and, indented, every ``###`` one, each linked to GitHub's anchor.
"""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LONG_PAGE = 300  # lines: a page longer than this opens with its contents
START = "<!-- contents: made by docs/make_contents.py -->"
END = "<!-- /contents -->"
HEADING = re.compile(r"^(#{2,3}) (.+?)\s*$")
FENCE = re.compile(r"^(```|~~~)")


# Written by tools, not by hand (bench and report-card outputs): left as they are made.
GENERATED = ("docs/data/", "docs/report-card/")
# Short, but a page a reader scans for one figure: it carries its contents too.
ALWAYS = ("docs/PERFORMANCE.md",)


def pages() -> list[Path]:
    """README and every hand-written Markdown page under docs/."""
    found = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
    return [page for page in found if not name_of(page).startswith(GENERATED)]


def name_of(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


def slug(title: str) -> str:
    """GitHub's anchor of a heading: lower case, markup and punctuation dropped (but ``-``
    and ``_``), each space a hyphen."""
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)  # a link's text only
    text = re.sub(r"[^\w\- ]", "", text.lower())
    return text.replace(" ", "-")


def headings(text: str) -> list[tuple[int, str, str]]:
    """(level, title, anchor) of each ``##``/``###`` heading outside code blocks; a repeated
    anchor gets GitHub's ``-1``, ``-2`` suffix."""
    found: list[tuple[int, str, str]] = []
    seen: dict[str, int] = {}
    fenced = False
    for line in text.splitlines():
        if FENCE.match(line):
            fenced = not fenced
            continue
        match = None if fenced else HEADING.match(line)
        if match is None:
            continue
        title = match.group(2)
        anchor = slug(title)
        count = seen.get(anchor, 0)
        seen[anchor] = count + 1
        found.append((len(match.group(1)), title, f"{anchor}-{count}" if count else anchor))
    return found


def contents(text: str) -> str:
    """The contents block of a page (its own headings, the contents excluded)."""
    body = strip(text)
    lines = [START, "**Contents**", ""]
    for level, title, anchor in headings(body):
        indent = "  " * (level - 2)
        shown = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", title)
        lines.append(f"{indent}- [{shown}](#{anchor})")
    return "\n".join([*lines, END])


def strip(text: str) -> str:
    """The page without its contents block."""
    return re.sub(rf"{re.escape(START)}.*?{re.escape(END)}\n\n?", "", text, flags=re.DOTALL)


def with_contents(text: str) -> str:
    """The page with its contents block, just after the first paragraph below the title."""
    body = strip(text)
    lines = body.split("\n")
    title = next((i for i, line in enumerate(lines) if line.startswith("# ")), 0)
    end = next((i for i, line in enumerate(lines)
                if i > title + 1 and not line.strip()), len(lines))
    head, tail = "\n".join(lines[:end]), "\n".join(lines[end + 1:])
    return f"{head}\n\n{contents(body)}\n\n{tail}"


def is_long(text: str) -> bool:
    """Whether the page, as it stands, is long enough to need its contents."""
    return len(text.splitlines()) > LONG_PAGE


def needs_contents(text: str) -> bool:
    """Long without its contents, or carrying contents to keep up to date."""
    return START in text or len(strip(text).splitlines()) > LONG_PAGE


def main() -> None:
    for page in pages():
        text = page.read_text()
        if not (needs_contents(text) or name_of(page) in ALWAYS):
            continue
        updated = with_contents(text)
        if updated != text:
            page.write_text(updated)
            print(f"contents written: {name_of(page)}")


if __name__ == "__main__":
    main()
