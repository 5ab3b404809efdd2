"""The clock's lean front (client/cli/lean.py, issue 47: ``status`` took 5 x ``--version``):
what it imports, checked in a fresh interpreter against a real daemon, never by timing; what
it reads from a command line, held to what typer reads from the same line; what it prints,
held to what the whole CLI prints through rich."""

from __future__ import annotations

import io
import json
import math
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import pytest
import typer.main
from support.cli import run

from galton.client import Client, EmbeddedDaemon
from galton.client.cli import console, lean, time, world
from galton.client.cli.plain import plain_table, status_rows, status_title
from galton.client.cli.root import make_app
from galton.client.cli.tables import ReadableConsole, status_table
from galton.protocol import SimStatus
from galton.protocol.operations import OPERATIONS
from galton.protocol.vocabulary import SimState

# What the lean front must not load: the CLI framework, its drawing, pydantic (typer's
# adapters), the operation table, the SDK and numpy.
NOT_LEAN = ("typer", "rich", "pydantic", "galton.protocol.operations", "importlib.metadata",
            "numpy", "zmq", "galton.client.sdk.client", "galton.client.cli.common")
ENTRY = """
import json, sys
sys.argv = ["galton-client", *json.loads(sys.argv[1])]
from galton.client.cli.{module} import main
try:
    main()
except SystemExit as done:
    code = done.code
else:
    code = 0
print(json.dumps([code, [m for m in {heavy!r} if m in sys.modules]]), file=sys.stderr)
"""


def entry(module: str, args: list[str]) -> tuple[int, list[str], str, str]:
    """Run ``module``'s main as the console does, into a pipe: exit code, the NOT_LEAN
    modules it loaded, stdout, and stderr less the probe's line."""
    done = subprocess.run(
        [sys.executable, "-c", ENTRY.format(module=module, heavy=NOT_LEAN), json.dumps(args)],
        capture_output=True, text=True, timeout=60, check=False,
        env={k: v for k, v in os.environ.items()
             if k not in ("COLUMNS", "FORCE_COLOR", "TTY_COMPATIBLE")})
    *errors, probe = done.stderr.splitlines()
    code, loaded = json.loads(probe)
    return code, loaded, done.stdout, "\n".join(errors)


@pytest.fixture
def target(mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> list[str]:
    return ["--connect", daemons["mujoco"].endpoint, "--instance", mujoco_sim.instance]


@pytest.mark.parametrize("command", [["status"], ["pause", "--json"]])
def test_a_clock_command_loads_neither_typer_rich_nor_the_operation_table(
        command: list[str], target: list[str], mujoco_sim: Client) -> None:
    code, loaded, out, _ = entry("console", [*target, *command])
    assert code == 0 and loaded == [], (loaded, out)
    assert mujoco_sim.instance in out
    # and it says what the whole CLI (typer, rich) says of the same world
    whole_code, whole_loaded, whole_out, _ = entry("app", [*target, *command])
    assert whole_code == 0 and "typer" in whole_loaded and "rich" in whole_loaded
    assert out == whole_out


def test_a_refusal_and_a_usage_error_read_as_on_the_whole_cli(target: list[str]) -> None:
    """The daemon's refusal is the lean front's to print; a bad value is typer's."""
    for args in (["--connect", target[1], "--instance", "nobody", "status"],
                 [*target, "reset", "--scope", "everything"]):
        lean_run, whole_run = entry("console", args), entry("app", args)
        assert lean_run[0] == whole_run[0] != 0 and lean_run[3] == whole_run[3], lean_run
        assert lean_run[3].startswith("galton-client: ") and lean_run[3].count("\n") == 0


def typer_reads(argv: list[str]) -> tuple[dict[str, Any], str, dict[str, Any]] | None:
    """The global options, command and command options typer reads from ``argv`` (None:
    it refuses the line)."""
    group = typer.main.get_command(make_app((world.commands, time.commands), ""))
    assert isinstance(group, typer.main.TyperGroup)
    try:
        ctx = group.make_context("galton-client", list(argv))
        words = [*getattr(ctx, "_protected_args", []), *ctx.args]  # the command and past it
        name, command, rest = group.resolve_command(ctx, words)
        assert name is not None and command is not None
        sub = command.make_context(name, rest, parent=ctx)
    except (typer.TyperException, typer.Exit):  # click's UsageError and its kin
        return None
    # typer hands a missing list option over as None, and an unset flag as False
    options = {**ctx.params, "connect": list(ctx.params["connect"]) or None,
               "show_version": bool(ctx.params["show_version"])}
    return options, name, sub.params


def lean_as_typer(line: lean.LeanLine) -> tuple[dict[str, Any], str, dict[str, Any]]:
    """A LeanLine in typer's terms, to compare with typer_reads."""
    names = {"password_file", "tls_ca", "tls_cert", "tls_key", "zmq_key"}
    options = {"connect": line.connect, "instance": line.instance, "timeout": line.timeout,
               "user": line.user, "zmq_server_key": line.zmq_server_key,
               "show_version": False, **{name: line.files.get(name) for name in names}}
    command = next(word for word, op in lean.OPERATION_OF.items() if op == line.op)
    own: dict[str, Any] = {"as_json": line.as_json, **line.args}
    if command == "play":
        own.setdefault("rtf", None)
    return options, command, own


TAKEN = [
    ["status"], ["status", "--json"], ["--instance", "a", "status"],
    ["--connect", "tcp/h:1", "--connect=tcp/h:2", "--instance=b", "--timeout", "2.5", "pause"],
    ["--timeout=1e-3", "stop", "--json"], ["play"], ["play", "--rtf", "0"],
    ["play", "--json", "--rtf=2.5"], ["set-rtf", "3"], ["set-rtf", "--json", "0.5"],
    ["reset"], ["reset", "--scope", "time", "--json"], ["reset", "--scope=spawned"],
    ["--user", "ann", "--password-file", "pw.txt", "status"],
    ["--zmq-key", "c.key_secret", "--zmq-server-key", "abc", "status"],
    ["--tls-ca", "ca.pem", "--tls-cert", "c.pem", "--tls-key", "c.key", "status"],
]
# Lines the lean front leaves to typer: help, version, and what typer refuses or might
# read otherwise.
LEFT = [
    ["--help"], ["status", "--help"], ["--version", "status"], ["status", "extra"],
    ["--timeout", "0", "status"], ["--timeout", "nan", "status"], ["--timeout", "x", "status"],
    ["play", "--rtf", "-1"], ["set-rtf", "-1"], ["set-rtf"], ["set-rtf", "1", "2"],
    ["play", "--rtf", "inf"], ["set-rtf", "1e7"],
    ["reset", "--scope", "every"], ["--instance", "status"], ["status", "--rtf", "1"],
    ["--instance", "a", "--instance", "b", "status"], ["--inst", "a", "status"],
    ["--password-file", ".", "status"], ["status", "--json", "--json"], ["spawn", "cube"],
]


@pytest.mark.parametrize("argv", TAKEN, ids=" ".join)
def test_the_lean_front_reads_a_line_as_typer_does(
        argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # the files named are not there: the same to both
    line = lean.parse(argv)
    assert line is not None
    assert typer_reads(argv) == lean_as_typer(line)  # a --scope typer reads is a StrEnum


@pytest.mark.parametrize("argv", LEFT, ids=" ".join)
def test_the_lean_front_leaves_help_and_doubtful_lines_to_typer(argv: list[str]) -> None:
    assert lean.parse(argv) is None


@pytest.mark.parametrize("argv", [["play", "--rtf", "inf"], ["set-rtf", "1e7"]], ids=" ".join)
def test_an_rtf_past_the_protocols_bound_is_a_usage_error(argv: list[str]) -> None:
    """As a negative one is: exit 2 from typer, naming the bound, before any daemon."""
    result = run(argv)
    assert result.exit_code == 2 and "1000000" in result.output, result.output


def test_the_lean_front_declares_what_the_cli_and_the_protocol_declare() -> None:
    """Its commands are console's and the clock groups', its options root.py's, and each
    operation waits the --timeout (what Target.call would give it)."""
    assert set(lean.OPERATION_OF) == console.LEAN_COMMANDS
    group = typer.main.get_command(make_app((world.commands, time.commands), ""))
    assert isinstance(group, typer.main.TyperGroup)
    valued = {name for param in group.params if not getattr(param, "is_flag", False)
              for name in param.opts}
    assert valued == set(lean.VALUE_OPTIONS)
    for word, op in lean.OPERATION_OF.items():
        assert word in group.commands and op == word.replace("-", "_")
        for seconds in (0.01, 5.0, 300.0):
            assert OPERATIONS[op].client_timeout(seconds) == seconds


STATUS = SimStatus(state=SimState.PLAYING, step=1234, sim_time=2.468, timestep=0.002,
                   target_rtf=1.0, rtf=0.987654, entity_count=7, engine="mujoco",
                   instance="galton", controller="c0ffee" * 6)


@pytest.mark.parametrize("status", [
    STATUS, replace(STATUS, controller=None), replace(STATUS, instance="a-much-longer-name-x"),
    replace(STATUS, instance="i" * 60), replace(STATUS, world="[bold]w"),
    replace(STATUS, sim_time=math.inf, faulted=True), replace(STATUS, world="é")],
    ids=["controlled", "free", "long-title", "long-instance", "markup", "inf", "accent"])
def test_the_plain_status_table_is_what_rich_draws_into_a_pipe(
        status: SimStatus, monkeypatch: pytest.MonkeyPatch) -> None:
    for hint in ("COLUMNS", "FORCE_COLOR", "TTY_COMPATIBLE", "TERM"):
        monkeypatch.delenv(hint, raising=False)
    drawn = ReadableConsole(file=io.StringIO())
    drawn.print(status_table(status))
    plain = plain_table(status_title(status), status_rows(status))
    assert plain is None or plain == drawn.file.getvalue()  # type: ignore[attr-defined]
    assert (plain is None) == any(mark in status.world for mark in "[é")  # left to rich
