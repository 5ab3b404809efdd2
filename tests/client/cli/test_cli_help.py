"""galton-client's command set and help, checked without any daemon: every operation of the
protocol has its command, and no help text shows reStructuredText markup."""

from __future__ import annotations

import re

import pytest
import typer.main
import typer.rich_utils
from support.cli import run

from galton.client.cli.app import app
from galton.client.cli.common import HELP_PIPE_WIDTH, help_text
from galton.protocol.operations import OPERATIONS

# Operations whose command is not the operation's name with dashes (README, "CLI").
COMMAND_OF_OPERATION = {"list": "entities", "get_params": "params", "set_params": "params",
                        "close_stream": "stream-states"}
# Operations reached only through `galton-client call` (docs/ARCHITECTURE.md: a new
# operation needs no command of its own; tests/client/cli/test_cli_call.py calls it).
CALL_ONLY = {"get_entities"}
RST_MARKUP = re.compile(r"``|:[a-z]+:`")


def commands() -> list[str]:
    return sorted(typer.main.get_command(app).commands)  # type: ignore[attr-defined]


def test_every_operation_has_a_command_besides_call() -> None:
    named = set(commands()) - {"call"}
    missing = [op for op in OPERATIONS if op not in CALL_ONLY
               and COMMAND_OF_OPERATION.get(op, op.replace("_", "-")) not in named]
    assert not missing, f"operations without a CLI command: {missing}"


@pytest.mark.parametrize("command", [None, *commands()])
def test_help_has_no_rst_markup_and_nothing_cut_in_a_pipe(
        command: str | None, monkeypatch: pytest.MonkeyPatch) -> None:
    # The width --help has in a pipe (galton.client.cli.common.widen_help_when_piped;
    # test_cli_pipes.py reads one through a real pipe): no cell cut to "…".
    monkeypatch.setattr(typer.rich_utils, "MAX_WIDTH", HELP_PIPE_WIDTH)
    result = run(["--help"] if command is None else [command, "--help"])
    assert result.exit_code == 0, result.output
    assert not RST_MARKUP.search(result.output), result.output
    assert "…" not in result.output, result.output


def test_help_text_joins_paragraph_lines_and_keeps_brackets() -> None:
    text = help_text("""Run ``step``, see :func:`get_states`.

    Two lines
    of one paragraph: [x].
    """)
    assert text == "Run step, see get_states.\n\nTwo lines of one paragraph: \\[x]."
