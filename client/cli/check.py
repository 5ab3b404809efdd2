"""``galton-client check RESULTS``: does a bench run meet the fidelity targets?

The trials of every results.json given are pooled and summarised as the bench's report does
(same Monte Carlo draws and seeds, so the same p), and each engine, release mode and ball
count is held to the fidelity targets of ``galton.analysis.targets``, the definition the
report's fidelity verdict uses too. Exit code 0 when every cell meets them, 1 when one
misses, 2 when the results cannot be read. Scoring needs scipy (the ``[bench]`` extra), so
it is imported inside the command: a client without it keeps every other command.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from galton.analysis.errors import AnalysisError
from galton.client.cli.common import JsonOpt, emit

if TYPE_CHECKING:
    from galton.analysis.records import TrialRecord
    from galton.analysis.targets import CellVerdict

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

UNREADABLE_EXIT = 2


def _load(paths: list[Path]) -> list[TrialRecord]:
    """The trials, or one clear line on stderr and exit code 2 when they cannot be read."""
    from galton.analysis.targets import load_trials
    try:
        return load_trials(paths)
    except AnalysisError as error:
        typer.echo(f"galton-client: {type(error).__name__}: {error}", err=True)
        raise typer.Exit(UNREADABLE_EXIT) from error


def _summary_line(cells: list[CellVerdict]) -> str:
    from galton.analysis.targets import TARGETS_TEXT
    met = sum(cell.passed for cell in cells)
    return f"{met} of {len(cells)} cells meet every target ({TARGETS_TEXT})"


@commands.command()
def check(
    results: Annotated[list[Path], typer.Argument(
        help="results.json files written by bench, or the folders holding them.")],
    as_json: JsonOpt = False,
) -> None:
    """Hold a bench run to the fidelity targets: one verdict per engine and ball count."""
    from galton.analysis.targets import TARGETS_TEXT, verdicts
    cells = verdicts(_load(results))
    passed = all(cell.passed for cell in cells)

    def render() -> None:
        for cell in cells:
            typer.echo(cell.line())
        typer.echo(_summary_line(cells))
    emit({"passed": passed, "targets": TARGETS_TEXT,
          "cells": [cell.to_dict() for cell in cells]}, as_json, render)
    if not passed:
        raise typer.Exit(1)
