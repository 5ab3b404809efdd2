"""The ``galton-client`` command's entry: ``--version`` answers before typer and the
commands are imported; anything else goes to the CLI (``galton.client.cli.app``)."""

from __future__ import annotations

import sys
from importlib.metadata import PackageNotFoundError, version


def main() -> None:
    if sys.argv[1:] == ["--version"]:
        try:
            print(f"galton-client {version('galton-bridge')}")
        except PackageNotFoundError:
            print("galton-client unknown (not installed)")
        return
    from galton.client.cli.app import main as cli_main

    cli_main()
