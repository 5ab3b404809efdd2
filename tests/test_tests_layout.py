"""tests/ mirrors the code's rooms: a client test sits in the folder of the client room it
tests (tests/client/<room>/), the helpers are one package (tests/support/), and no two test
modules share a name (pytest imports each by its bare name: a clash stops the collection)."""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import galton.client

TESTS = Path(__file__).resolve().parent
CLIENT_ROOMS = {p.name for p in Path(galton.client.__file__).parent.iterdir()
                if (p / "__init__.py").exists()}
ABOUT_EVERY_ROOM = {"test_layout.py"}  # tests/client/: the rooms' imports, all at once


def test_every_client_test_is_in_its_rooms_folder() -> None:
    client_tests = TESTS / "client"
    top = {p.name for p in client_tests.glob("test_*.py")}
    assert top == ABOUT_EVERY_ROOM
    folders = {p.parent.name for p in client_tests.rglob("test_*.py")
               if p.parent != client_tests}
    assert folders <= CLIENT_ROOMS, f"tests/client/ folders that are no client room: {folders}"
    assert {"sdk", "cli", "bench", "view"} <= folders


def test_the_helpers_are_one_package() -> None:
    loose = {p.name for p in TESTS.glob("*.py")} - {"conftest.py"}
    assert {name for name in loose if not name.startswith("test_")} == set(), (
        "a helper module belongs in tests/support/")
    assert (TESTS / "support" / "__init__.py").exists()


def test_no_two_test_modules_share_a_name() -> None:
    names = Counter(p.name for p in TESTS.rglob("test_*.py"))
    assert [name for name, count in names.items() if count > 1] == []
