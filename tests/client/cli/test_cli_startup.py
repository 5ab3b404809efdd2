"""A command line's start loads only what it needs (issue 33: each command took 0.9 s, most
of it numpy, Zenoh, ZeroMQ and the bench's analysis imported for every command). Checked
by what a fresh interpreter has imported, not by timing."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from galton.client import Client, EmbeddedDaemon

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


# What a command that only asks a daemon (or sets its clock) must not load: the SDK's Client
# and numpy (issue 47: status took 7.6 x --version, loading numpy and the whole SDK), nor
# pyzmq for a Zenoh endpoint.
ASKING = ("numpy", "zmq", "scipy", "matplotlib", "galton.client.sdk.client",
          "galton.protocol.model")


@pytest.mark.parametrize(("command", "shows"), [(["status"], "mujoco"),
                                               (["pause", "--json"], '"state": "paused"')])
def test_a_command_that_asks_a_daemon_loads_neither_numpy_nor_the_sdk(
        command: list[str], shows: str, mujoco_sim: Client,
        daemons: dict[str, EmbeddedDaemon]) -> None:
    args = ["--connect", daemons["mujoco"].endpoint, "--instance", mujoco_sim.instance,
            *command]
    probe = PROBE.replace("contextlib.redirect_stdout(io.StringIO())",
                          "contextlib.redirect_stdout(out := io.StringIO())")
    probe += "print(out.getvalue())\n"
    done = subprocess.run([sys.executable, "-c", probe.format(args=args, heavy=ASKING)],
                          capture_output=True, text=True, timeout=60, check=True)
    lines = done.stdout.splitlines()
    code, loaded = json.loads(lines[0])
    assert code in (0, None) and loaded == [], done.stdout  # None: the command returned
    shown = "\n".join(lines[1:])
    assert mujoco_sim.instance in shown and shows in shown, shown
