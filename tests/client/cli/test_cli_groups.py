"""The CLI's command groups: each module of ``galton.client.cli`` that declares commands is
in the one registration list (``COMMAND_GROUPS``), and no command name is taken twice."""

from __future__ import annotations

import importlib
import pkgutil

import typer
import typer.main

import galton.client.cli
from galton.client.cli.app import COMMAND_GROUPS, app


def declared_groups() -> dict[str, typer.Typer]:
    """Every module of the CLI package that holds a ``commands`` group, by module name."""
    found = {}
    for module_info in pkgutil.iter_modules(galton.client.cli.__path__):
        module = importlib.import_module(f"galton.client.cli.{module_info.name}")
        group = getattr(module, "commands", None)
        if isinstance(group, typer.Typer):
            found[module_info.name] = group
    return found


def test_every_declared_group_is_registered_once() -> None:
    declared = declared_groups()
    assert declared, "no command group found"
    missing = [name for name, group in declared.items() if group not in COMMAND_GROUPS]
    assert not missing, f"command groups not in COMMAND_GROUPS: {missing}"
    assert len(set(map(id, COMMAND_GROUPS))) == len(COMMAND_GROUPS) == len(declared)


def test_each_command_name_belongs_to_one_group() -> None:
    names = [info.name or typer.main.get_command_name(info.callback.__name__)
             for group in COMMAND_GROUPS for info in group.registered_commands
             if info.callback is not None]
    assert len(names) == len(set(names)), sorted(n for n in names if names.count(n) > 1)
    listed = typer.main.get_command(app).commands  # type: ignore[attr-defined]
    assert set(names) == set(listed)
