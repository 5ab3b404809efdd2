"""The core's two faces. A front reaches the core only through its call interface: each
module under daemon/fronts/ imports, of the daemon, nothing but ``core.calls`` (``Call``,
``CallPort``), ``access`` and other fronts' modules (the protocol and third parties are
free). A handler sees the loop only as an ``OpContext``: only the composition root imports
the loop. Read from the source, imports inside functions and under TYPE_CHECKING included."""

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
        "def f() -> None:\n    import galton.daemon.world.world\n")
    assert breaches(tmp_path / "fronts") == [
        "fronts/bad.py imports galton.daemon.core.loop.SimLoop",
        "fronts/bad.py imports galton.daemon.world.world"]


# The loop itself: built by the composition root. Handlers and helpers (its status board,
# its replies) see it through Protocols (daemon/core/context.py, loop_status.Watched).
MAY_IMPORT_THE_LOOP = {"server.py", "core/loop.py"}


def loop_importers(root: Path) -> set[str]:
    return {str(path.relative_to(root)) for path in root.rglob("*.py")
            if any(module == "galton.daemon.core.loop"
                   or module.startswith("galton.daemon.core.loop.")
                   for module in daemon_imports(path))}


def test_only_the_composition_root_imports_the_loop() -> None:
    assert loop_importers(DAEMON) <= MAY_IMPORT_THE_LOOP


def test_a_handler_importing_the_loop_is_seen(tmp_path: Path) -> None:
    (tmp_path / "ops").mkdir()
    (tmp_path / "ops" / "late.py").write_text("from galton.daemon.core import loop\n")
    (tmp_path / "ops" / "typed.py").write_text(
        "from galton.daemon.core.loop import SimLoop\n")
    (tmp_path / "ops" / "fine.py").write_text(
        "from galton.daemon.core.context import OpContext\n")
    assert loop_importers(tmp_path) == {"ops/late.py", "ops/typed.py"}
