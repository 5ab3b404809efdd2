"""A command line's start loads only what it needs (issue 33: each command took 0.9 s, most
of it numpy, Zenoh, ZeroMQ and the bench's analysis imported for every command). Checked
by what a fresh interpreter has imported, not by timing."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

HEAVY = ("numpy", "zenoh", "zmq", "scipy", "matplotlib", "galton.client.sdk.client",
         "galton.analysis.board")
PROBE = """
import contextlib, io, json, sys
from galton.client.cli.app import app
with contextlib.redirect_stdout(io.StringIO()):
    code = app({args!r}, standalone_mode=False)
print(json.dumps([code, [m for m in {heavy!r} if m in sys.modules]]))
"""


@pytest.mark.parametrize("args", [["--help"], ["bench", "--help"], ["spawn", "--help"],
                                  ["load-model", "--help"], ["view", "--help"],
                                  ["stream-states", "--help"]])
def test_help_imports_none_of_the_heavy_libraries(args: list[str]) -> None:
    done = subprocess.run([sys.executable, "-c", PROBE.format(args=args, heavy=HEAVY)],
                          capture_output=True, text=True, timeout=60, check=True)
    code, loaded = json.loads(done.stdout.splitlines()[-1])
    assert code == 0 and loaded == []


def test_version_answers_before_the_cli_is_imported() -> None:
    probe = ("import sys; sys.argv = ['galton-client', '--version']\n"
             "from galton.client.cli.console import main; main()\n"
             "print('typer' in sys.modules, 'galton.client.cli.app' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=60, check=True)
    first, second = done.stdout.splitlines()
    assert first.startswith("galton-client ") and second == "False False"
