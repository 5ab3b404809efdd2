"""Helpers of the galton-client tests: run the CLI in process through typer's runner."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path
from typing import Any

from typer.testing import CliRunner, Result

from galton.client import EmbeddedDaemon
from galton.client.cli.app import app

runner = CliRunner()
# The real console command, installed beside this interpreter.
CONSOLE_COMMAND = str(Path(sys.executable).with_name("galton-client"))
NOWHERE = ["--connect", "tcp/127.0.0.1:1"]  # nothing listens there


def target_of(daemon: EmbeddedDaemon) -> list[str]:
    """The global options that point the CLI at one daemon."""
    return ["--connect", daemon.endpoint, "--instance", daemon.instance]


def run(args: list[str]) -> Result:
    return runner.invoke(app, args)


def invoke(args: list[str]) -> Any:
    """Run a command that must succeed; return its JSON output."""
    result = run(args)
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


def flat(text: str) -> str:
    """Output without Rich's box drawing and line wrapping, for matching phrases."""
    return re.sub(r"\s+", " ", re.sub(r"[│╭╮╰╯─]", " ", text)).strip()
