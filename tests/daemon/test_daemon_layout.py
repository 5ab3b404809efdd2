"""The daemon's layout holds (issue 36): engines stay behind the registry and their base,
no module reaches into an engine's private state from outside its package, and the
daemon's top level stays small. Pure source reads: no engine is imported."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DAEMON = ROOT / "daemon"
ENGINES = DAEMON / "engines"
SOURCES = ("daemon", "client", "protocol", "analysis")
MAX_TOP_LEVEL_MODULES = 10
ENGINE_PACKAGES = sorted(p.name for p in ENGINES.iterdir()
                         if (p / "engine.py").is_file())
# What an engine package may import of ours besides itself: the engine base (the modules at
# the top of engines/: the contract base.py, its parameter specs params.py, what engines
# share) and the protocol; never the registry, the checker, another engine or the daemon.
ENGINE_MAY_IMPORT = (*(f"galton.daemon.engines.{p.stem}" for p in sorted(ENGINES.glob("*.py"))
                       if p.stem != "__init__"), "galton.protocol")
PRIVATE_REACH = re.compile(r"\bengine\._[a-z]")


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(("galton", *parts))


def imported(path: Path) -> list[str]:
    """Every module an import statement of this file names (``from a import b``: a.b too,
    since b may be a module)."""
    names: list[str] = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names += [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.append(node.module)
            names += [f"{node.module}.{alias.name}" for alias in node.names]
    return names


def sources() -> list[Path]:
    return sorted(p for folder in SOURCES for p in (ROOT / folder).rglob("*.py"))


def owner(path: Path) -> str | None:
    """The engine package a file belongs to, if any."""
    parts = path.relative_to(ENGINES).parts if path.is_relative_to(ENGINES) else ()
    return parts[0] if len(parts) > 1 and parts[0] in ENGINE_PACKAGES else None


def test_the_engine_packages_and_base_are_found() -> None:
    assert set(ENGINE_PACKAGES) >= {"mujoco", "pybullet", "dart", "ode"}
    assert {"galton.daemon.engines.base", "galton.protocol"} <= set(ENGINE_MAY_IMPORT)


def test_the_daemon_top_level_stays_small() -> None:
    modules = sorted(p.name for p in DAEMON.glob("*.py"))
    assert len(modules) <= MAX_TOP_LEVEL_MODULES, modules


@pytest.mark.parametrize("package", ENGINE_PACKAGES)
def test_only_the_engine_package_imports_its_modules(package: str) -> None:
    """Everyone else reaches an engine through the registry (engines/__init__.py), which
    names it in a string, and the contract (engines/base.py)."""
    prefix = f"galton.daemon.engines.{package}"
    offenders = [f"{p.relative_to(ROOT)} imports {name}" for p in sources()
                 if owner(p) != package
                 for name in imported(p) if name == prefix or name.startswith(prefix + ".")]
    assert offenders == []


@pytest.mark.parametrize("package", ENGINE_PACKAGES)
def test_an_engine_package_imports_only_the_base_and_the_protocol(package: str) -> None:
    own = f"galton.daemon.engines.{package}"
    allowed = (own, *ENGINE_MAY_IMPORT)
    offenders = [f"{p.relative_to(ROOT)} imports {name}"
                 for p in sorted((ENGINES / package).rglob("*.py"))
                 for name in imported(p) if name.startswith("galton")
                 and name != "galton.daemon.engines"  # the parent of base, as Python has it
                 and not any(name == a or name.startswith(a + ".") for a in allowed)]
    assert offenders == []


def test_no_module_reaches_an_engines_private_state_from_outside() -> None:
    offenders = [f"{p.relative_to(ROOT)}:{number}: {line.strip()}" for p in sources()
                 if owner(p) is None
                 for number, line in enumerate(p.read_text().splitlines(), 1)
                 if PRIVATE_REACH.search(line)]
    assert offenders == []


def test_the_checks_see_a_reach_and_an_import(tmp_path: Path) -> None:
    """The checks above can fail: they find what they look for in a made-up module."""
    fake = tmp_path / "fake.py"
    fake.write_text("from galton.daemon.engines.mujoco import engine\nx = engine._model\n")
    assert "galton.daemon.engines.mujoco.engine" in imported(fake)
    assert PRIVATE_REACH.search(fake.read_text().splitlines()[1])
