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


def test_the_lean_commands_are_the_clock_groups_and_the_flags_the_roots() -> None:
    """console.py runs LEAN_COMMANDS on a CLI of the world and time groups alone, and finds
    the command past the global options knowing which of them take no value."""
    import typer.main

    from galton.client.cli import console, time, world
    from galton.client.cli.root import make_app

    lean = typer.main.get_command(make_app((world.commands, time.commands), ""))
    assert isinstance(lean, typer.main.TyperGroup)
    assert set(lean.commands) >= console.LEAN_COMMANDS
    flags = {name for param in lean.params if getattr(param, "is_flag", False)
             for name in param.opts}
    assert flags | {"--help"} == console.GLOBAL_FLAGS
    assert console.command_word(["--connect", "tcp/x:1", "--instance=a", "status"]) == "status"
    assert console.command_word(["--help", "status"]) is None
    assert console.command_word(["spawn", "sphere", "b"]) == "spawn"


def test_status_on_the_lean_cli_says_what_the_whole_cli_says(
        mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> None:
    """The same status, through console.main's lean path and through the whole CLI; the
    lean path imports no other group."""
    args = ["--connect", daemons["mujoco"].endpoint, "--instance", mujoco_sim.instance,
            "status", "--json"]
    probe = (f"import json, sys\nsys.argv = ['galton-client', *{args!r}]\n"
             "from galton.client.cli.console import main\n"
             "try:\n    main()\nexcept SystemExit:\n    pass\n"
             "print(json.dumps(['galton.client.cli.bench' in sys.modules, "
             "'galton.client.cli.app' in sys.modules]))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=60, check=True)
    *shown, loaded = done.stdout.splitlines()
    assert json.loads(loaded) == [False, False]
    whole = subprocess.run([sys.executable, "-c", PROBE.replace(
        "contextlib.redirect_stdout(io.StringIO())",
        "contextlib.redirect_stdout(out := io.StringIO())").format(args=args, heavy=())
        + "print(out.getvalue())\n"], capture_output=True, text=True, timeout=60, check=True)
    lean_status, whole_status = json.loads("\n".join(shown)), json.loads(
        "\n".join(whole.stdout.splitlines()[1:]))
    assert lean_status.keys() == whole_status.keys()
    assert lean_status["instance"] == whole_status["instance"] == mujoco_sim.instance
