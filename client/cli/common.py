"""What every command of the CLI shares: the target the global options point at, one
client per command, errors as one line, tables, JSON output and help text."""

from __future__ import annotations

import inspect
import json
import os
import re
import sys
from collections.abc import Callable
from dataclasses import asdict
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from rich.markup import escape

from galton.client.cli.plain import error_line
from galton.client.cli.tables import KEY_WIDTH as KEY_WIDTH  # the commands import these
from galton.client.cli.tables import PIPE_WIDTH as PIPE_WIDTH  # from here (issue 33)
from galton.client.cli.tables import ReadableConsole as ReadableConsole
from galton.client.cli.tables import console as console
from galton.client.cli.tables import readable as readable
from galton.client.cli.tables import status_table, unlimited_width
from galton.client.transport.credentials import Credentials
from galton.protocol import GaltonError

if TYPE_CHECKING:  # the SDK (numpy, Zenoh, ZeroMQ) is imported when a command needs it
    from galton.client.sdk.client import Client, Stamp
    from galton.client.transport.zmq_keys import ZmqKeys
    from galton.protocol import SimStatus

HELP_PIPE_WIDTH = 160  # --help into a pipe: wide enough that no cell is cut to "…"


def widen_help_when_piped() -> None:
    """--help into a pipe at HELP_PIPE_WIDTH columns instead of rich's 80, which cut long
    words in the options' help to "…" (TERMINAL_WIDTH, when set, still decides)."""
    if unlimited_width(sys.stdout.isatty()) and not os.environ.get("TERMINAL_WIDTH"):
        os.environ["TERMINAL_WIDTH"] = str(HELP_PIPE_WIDTH)
        rich_utils = sys.modules.get("typer.rich_utils")
        if rich_utils is not None:
            rich_utils.MAX_WIDTH = HELP_PIPE_WIDTH  # type: ignore[attr-defined]


T = TypeVar("T")
PACKAGE = "galton-bridge"

JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON for scripts.")]


class Target:
    """Where the global options point: endpoints, instance, timeout, credentials."""

    def __init__(self, connect: list[str] | None, instance: str, timeout: float,
                 credentials: Credentials | None = None,
                 zmq_keys: ZmqKeys | None = None) -> None:
        self.connect = connect
        self.instance = instance
        self.timeout = timeout
        self.credentials = credentials
        self.zmq_keys = zmq_keys

    def client(self, client_id: str | None = None) -> Client:
        from galton.client.sdk.client import Client
        from galton.client.transport.base import zmq_endpoint

        over_zmq = zmq_endpoint(self.connect) is not None
        return Client(self.instance, self.connect, timeout=self.timeout,
                      credentials=None if over_zmq else self.credentials,
                      zmq_keys=self.zmq_keys if over_zmq else None, client_id=client_id)

    def call(self, op: str, args: dict[str, Any] | None = None) -> dict[str, Any]:
        """One request and its result map, through the transport alone (lean.ask: neither
        the SDK's Client nor numpy), so a command that only asks or sets the clock (status,
        play, pause ...) starts sooner. A refusal raises its typed error, as the SDK's does."""
        from galton.client.cli.lean import ask
        from galton.protocol.operations import OPERATIONS

        return ask(self.connect, self.instance, OPERATIONS[op].client_timeout(self.timeout),
                   self.credentials, self.zmq_keys, op, args)


def package_version() -> str:
    """The installed distribution's version (one source of truth: pyproject.toml)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return "unknown (not installed)"



def fail(error: GaltonError) -> typer.Exit:
    """Print the error's line on stderr; return the exit (code 1) to raise."""
    typer.echo(f"galton-client: {error_line(error)}", err=True)
    return typer.Exit(1)


def run_guarded(action: Callable[[], T]) -> T:
    """Turn any galton error into one clear line on stderr and exit code 1."""
    try:
        return action()
    except GaltonError as error:
        raise fail(error) from error


def emit(data: Any, as_json: bool, render: Callable[[], None]) -> None:
    if as_json:
        typer.echo(json.dumps(data, indent=2, default=str))
    else:
        render()


def with_client(ctx: typer.Context, action: Callable[[Client], T]) -> T:
    """Run one action on a client of the global target, errors turned into exit code 1."""
    target: Target = ctx.obj

    def go() -> T:
        with target.client() as client:
            return action(client)
    return run_guarded(go)


def status_call(ctx: typer.Context, op: str, args: dict[str, Any] | None = None
                ) -> SimStatus:
    """An operation that answers the clock (status, play, pause ...), without the SDK
    (Target.call); errors turned into exit code 1."""
    from galton.protocol.status import SimStatus
    target: Target = ctx.obj
    return run_guarded(lambda: SimStatus.from_wire(target.call(op, args)))


def show_status(status: SimStatus, as_json: bool) -> None:
    def render() -> None:
        console.print(status_table(status))
    emit(asdict(status), as_json, render)


def show_stamp(what: str, stamp: Stamp, as_json: bool, **extra: Any) -> None:
    """A mutation's outcome: what was done and the step and sim time it took effect at."""
    emit({**extra, **asdict(stamp)}, as_json, lambda: console.print(
        f"{what} at step {stamp.step}, sim time {stamp.sim_time:.4f} s", markup=False))


_RST_LITERAL = re.compile(r"``(.+?)``")
_RST_ROLE = re.compile(r":[a-z]+:`(.+?)`")


def help_text(docstring: str) -> str:
    """A docstring as help: RST literals and roles as plain words, each paragraph one line
    (typer keeps line breaks after the first), and no Rich markup (brackets stay brackets)."""
    text = _RST_ROLE.sub(r"\1", _RST_LITERAL.sub(r"\1", inspect.cleandoc(docstring)))
    paragraphs = (" ".join(line.strip() for line in p.splitlines()) for p in text.split("\n\n"))
    return escape("\n\n".join(paragraphs))


def tidy_help(typer_app: typer.Typer) -> None:
    """Give every command of ``typer_app`` its docstring as help_text renders it."""
    typer_app.info.help = help_text(str(typer_app.info.help or ""))
    for command in typer_app.registered_commands:
        doc = command.help or (command.callback.__doc__ if command.callback else None)
        if doc:
            command.help = help_text(doc)
