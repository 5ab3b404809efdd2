"""The ``galton-client`` command's entry: ``--version`` answers before typer and the
commands are imported; a command that only asks a daemon for its clock (``status``,
``play``, ``pause`` ...) runs on the lean front (``lean.py``: no typer, rich or pydantic),
or, for what that front leaves to typer (help, a bad value), on a typer CLI of its own two
groups (issue 47: ``status`` took 6.8 x ``--version`` while every group was imported and
built); anything else goes to the whole CLI (``galton.client.cli.app``)."""

from __future__ import annotations

import sys
from collections.abc import Sequence

# The clock's commands (groups world and time); tests/client/cli/test_cli_startup.py holds
# this to those groups' registrations and to the whole CLI's output.
LEAN_COMMANDS = frozenset({"status", "play", "set-rtf", "pause", "stop", "reset"})
# The global options that take no value (test_cli_startup.py holds it to root.py's).
GLOBAL_FLAGS = frozenset({"--version", "--help"})


def command_word(args: Sequence[str]) -> str | None:
    """The command a command line names past the global options; None when a global flag
    (help, version) or a short option comes first."""
    index = 0
    while index < len(args):
        word = args[index]
        if not word.startswith("-"):
            return word
        if word in GLOBAL_FLAGS or not word.startswith("--"):
            return None
        index += 1 if "=" in word else 2
    return None


def main() -> None:
    if sys.argv[1:] == ["--version"]:
        from importlib.metadata import PackageNotFoundError, version
        try:
            print(f"galton-client {version('galton-bridge')}")
        except PackageNotFoundError:
            print("galton-client unknown (not installed)")
        return
    if command_word(sys.argv[1:]) in LEAN_COMMANDS:
        from galton.client.cli.lean import run as run_lean
        code = run_lean(sys.argv[1:])
        if code is not None:
            sys.exit(code)
        from galton.client.cli import time, world
        from galton.client.cli.root import make_app, run

        run(make_app((world.commands, time.commands), "galton-client: a daemon's clock."))
        return
    from galton.client.cli.app import main as cli_main

    cli_main()
