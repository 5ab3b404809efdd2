"""A front reaches the core only through its call interface: each module under
daemon/fronts/ imports, of the daemon, nothing but ``core.calls`` (``Call``, ``CallPort``),
``access`` and other fronts' modules (the protocol and third parties are free). Read from
the source, imports inside functions and under TYPE_CHECKING included."""

from __future__ import annotations

import ast
from pathlib import Path

import galton.daemon

DAEMON = Path(galton.daemon.__file__).parent
ALLOWED = ("galton.daemon.core.calls", "galton.daemon.access", "galton.daemon.fronts")


def daemon_imports(path: Path) -> set[str]:
    """Every ``galton.daemon`` module a file imports (``from galton.daemon.x import y``
    counts as ``galton.daemon.x.y``: y may be a module)."""
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.update(f"{node.module}.{alias.name}" for alias in node.names)
    return {module for module in found if module.startswith("galton.daemon")}


def breaches(fronts: Path) -> list[str]:
    return [f"{path.relative_to(fronts.parent)} imports {module}"
            for path in sorted(fronts.rglob("*.py"))
            for module in sorted(daemon_imports(path))
            if not any(module == allowed or module.startswith(allowed + ".")
                       for allowed in ALLOWED)]


def test_a_front_imports_only_the_cores_call_interface() -> None:
    assert not breaches(DAEMON / "fronts")


def test_a_breach_is_seen(tmp_path: Path) -> None:
    (tmp_path / "fronts").mkdir()
    (tmp_path / "fronts" / "bad.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "from galton.daemon.core.calls import Call\n"
        "if TYPE_CHECKING:\n    from galton.daemon.core.loop import SimLoop\n"
        "def f() -> None:\n    import galton.daemon.world.scene\n")
    assert breaches(tmp_path / "fronts") == [
        "fronts/bad.py imports galton.daemon.core.loop.SimLoop",
        "fronts/bad.py imports galton.daemon.world.scene"]
