"""Pages a reader can navigate: every long page (README and docs/, over 300 lines) opens
with its contents, made from its own headings (docs/make_contents.py), and the performance
page stays a results page (its history lives in docs/research/performance-notebook.md)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[2]
PERFORMANCE_MAX_LINES = 300


def contents_tool() -> ModuleType:
    spec = importlib.util.spec_from_file_location("make_contents",
                                                  ROOT / "docs" / "make_contents.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


TOOL = contents_tool()
LONG = [page for page in TOOL.pages() if TOOL.is_long(page.read_text())]


def test_the_long_pages_are_found() -> None:
    names = {TOOL.name_of(page) for page in LONG}
    assert {"README.md", "docs/protocol.md", "docs/PHYSICS.md"} <= names


@pytest.mark.parametrize("page", LONG, ids=[TOOL.name_of(page) for page in LONG])
def test_a_long_page_opens_with_its_contents(page: Path) -> None:
    text = page.read_text()
    first_section = text.index("\n## ")
    assert TOOL.START in text[:first_section], (
        f"{TOOL.name_of(page)} is over {TOOL.LONG_PAGE} lines and opens with no contents: "
        "run python docs/make_contents.py")
    assert TOOL.with_contents(text) == text, (
        f"{TOOL.name_of(page)}'s contents are stale: run python docs/make_contents.py")


def test_every_contents_link_reaches_a_heading() -> None:
    for page in TOOL.pages():
        text = page.read_text()
        if TOOL.START not in text:
            continue
        anchors = {anchor for _, _, anchor in TOOL.headings(TOOL.strip(text))}
        block = text[text.index(TOOL.START):text.index(TOOL.END)]
        linked = [line.split("](#")[1].rstrip(")") for line in block.splitlines()
                  if "](#" in line]
        assert linked and set(linked) <= anchors, TOOL.name_of(page)


def test_the_performance_page_is_a_results_page() -> None:
    page = (ROOT / "docs" / "PERFORMANCE.md").read_text()
    assert len(page.splitlines()) <= PERFORMANCE_MAX_LINES
    assert "research/performance-notebook.md" in page
    assert TOOL.START in page


def test_the_slug_is_githubs() -> None:
    assert TOOL.slug("`get_params` / `set_params`") == "get_params--set_params"
    assert TOOL.slug("Real-time factor, against balls (issue 6)") == (
        "real-time-factor-against-balls-issue-6")
    titles = [anchor for _, _, anchor in TOOL.headings("## Pool\n\n## Pool\n```\n## x\n```\n")]
    assert titles == ["pool", "pool-1"]
