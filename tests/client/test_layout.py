"""The client's rooms (its subpackages) and what each may import: transport
needs no other room, the SDK only transport, the tools built on the SDK (bench, laws, fuzz,
view, report card) no CLI, and no client module imports the daemon. Read from the source,
imports inside functions and under TYPE_CHECKING included."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import galton.client

CLIENT = Path(galton.client.__file__).parent
ALL_ROOMS = frozenset({"transport", "sdk", "fuzz", "bench", "laws", "report_card", "view",
                       "cli"})
# Each room: the other rooms it may import.
MAY_IMPORT: dict[str, frozenset[str]] = {
    "transport": frozenset(),
    "sdk": frozenset({"transport"}),
    "fuzz": frozenset({"sdk", "transport"}),
    "bench": frozenset({"sdk", "transport"}),
    "laws": frozenset({"sdk", "transport"}),
    "view": frozenset({"sdk", "transport"}),
    "report_card": frozenset({"sdk", "transport", "bench", "laws"}),
    "cli": ALL_ROOMS - {"cli"},
}


def imported_modules(path: Path) -> set[str]:
    """Every absolute module a file imports (``from galton.client import X``: X counts as
    ``galton.client.X``, a room or a name of the public face, which is the SDK's)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            if node.module == "galton.client":
                found.update(f"galton.client.{alias.name}" for alias in node.names)
    return found


def room_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[:2] != ["galton", "client"] or len(parts) < 3:
        return None
    return parts[2] if parts[2] in ALL_ROOMS else "sdk"  # a public name: the SDK's face


def breaches(room: str, root: Path = CLIENT) -> list[str]:
    found = []
    for path in sorted((root / room).rglob("*.py")):
        for module in sorted(imported_modules(path)):
            other = room_of(module)
            if module.startswith("galton.daemon") or (
                    other not in (None, room) and other not in MAY_IMPORT[room]):
                found.append(f"{path.relative_to(root)} imports {module}")
    return found


def test_every_room_has_its_rule() -> None:
    folders = {p.name for p in CLIENT.iterdir() if (p / "__init__.py").is_file()}
    assert folders == ALL_ROOMS


@pytest.mark.parametrize("room", sorted(ALL_ROOMS))
def test_a_room_imports_only_the_rooms_below_it(room: str) -> None:
    assert not breaches(room)


def test_a_breach_is_seen(tmp_path: Path) -> None:
    (tmp_path / "transport").mkdir()
    (tmp_path / "transport" / "late.py").write_text(
        "def f() -> None:\n    from galton.client.cli.common import console\n")
    (tmp_path / "transport" / "face.py").write_text("from galton.client import Client\n")
    (tmp_path / "transport" / "own.py").write_text("import galton.client.transport.base\n")
    (tmp_path / "sdk").mkdir()
    (tmp_path / "sdk" / "deep.py").write_text("import galton.daemon.cli\n")
    assert breaches("transport", tmp_path) == [
        "transport/face.py imports galton.client.Client",
        "transport/late.py imports galton.client.cli.common"]
    assert breaches("sdk", tmp_path) == ["sdk/deep.py imports galton.daemon.cli"]
