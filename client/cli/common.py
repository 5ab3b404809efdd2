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
from importlib.metadata import PackageNotFoundError, version
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from rich import box
from rich.console import Console, ConsoleDimensions
from rich.markup import escape
from rich.table import Table

from galton.client.transport.credentials import Credentials
from galton.protocol import (
    AccessDeniedError,
    DaemonUnreachableError,
    GaltonError,
    RemoteError,
    RequestTimeoutError,
)

if TYPE_CHECKING:  # the SDK (numpy, Zenoh, ZeroMQ) is imported when a command needs it
    from galton.client.sdk.client import Client, Stamp
    from galton.client.transport.zmq_keys import ZmqKeys
    from galton.protocol import SimStatus

class ReadableConsole(Console):
    """A console whose tables keep every character: in a terminal, the first column (the
    names a user types back: joints, links, parameters) as wide as its longest cell (up to
    KEY_WIDTH), the others folded onto more lines instead of cut to "…", light borders;
    into a pipe or a file (no terminal, no COLUMNS), as wide as they are: nothing folded,
    nothing cut (rich would otherwise assume 80 columns)."""

    @property
    def size(self) -> ConsoleDimensions:
        measured = Console.size.fget(self)  # type: ignore[attr-defined]
        if self._width is None and unlimited_width(self.is_terminal):  # no width was set
            return ConsoleDimensions(PIPE_WIDTH, measured.height)
        return measured  # type: ignore[no-any-return]

    @size.setter
    def size(self, new_size: tuple[int, int]) -> None:
        Console.size.fset(self, new_size)  # type: ignore[attr-defined]

    def print(self, *objects: Any, **kwargs: Any) -> None:
        for item in objects:
            if isinstance(item, Table):
                readable(item)
        super().print(*objects, **kwargs)


KEY_WIDTH = 40
PIPE_WIDTH = 10_000  # "unlimited": a table or line is as wide as its text
HELP_PIPE_WIDTH = 160  # --help into a pipe: wide enough that no cell is cut to "…"


def unlimited_width(is_terminal: bool) -> bool:
    """Whether output goes where nobody reads it at a terminal's width (a pipe, a file)
    and no width was asked for (COLUMNS)."""
    return not is_terminal and not os.environ.get("COLUMNS")


def widen_help_when_piped() -> None:
    """--help into a pipe at HELP_PIPE_WIDTH columns instead of rich's 80, which cut long
    words in the options' help to "…" (TERMINAL_WIDTH, when set, still decides)."""
    if unlimited_width(sys.stdout.isatty()) and not os.environ.get("TERMINAL_WIDTH"):
        os.environ["TERMINAL_WIDTH"] = str(HELP_PIPE_WIDTH)
        rich_utils = sys.modules.get("typer.rich_utils")
        if rich_utils is not None:
            rich_utils.MAX_WIDTH = HELP_PIPE_WIDTH  # type: ignore[attr-defined]


def readable(table: Table) -> None:
    table.box = box.SIMPLE_HEAD
    for index, column in enumerate(table.columns):
        column.overflow = "fold"
        if index == 0:
            cells = [len(str(cell)) for cell in column.cells]
            column.min_width = min(KEY_WIDTH, max([len(str(column.header)), *cells]))


console = ReadableConsole()
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
        """One request and its result map, through the transport alone: the SDK's Client
        (numpy, and pyzmq unless the endpoint is a zmq+ one) is not imported, so a command
        that only asks or sets the clock (status, play, pause ...) starts sooner. A refusal
        raises its typed error, as the SDK's does."""
        import uuid

        from galton.client.transport.base import transport_for, zmq_endpoint
        from galton.protocol import Keys
        from galton.protocol.operations import OPERATIONS

        over_zmq = zmq_endpoint(self.connect) is not None
        client_id = uuid.uuid4().hex  # as the SDK's: a request names its client
        transport = transport_for(Keys(self.instance), client_id, self.connect,
                                  credentials=None if over_zmq else self.credentials,
                                  zmq_keys=self.zmq_keys if over_zmq else None)
        try:
            reply = transport.request(op, args, OPERATIONS[op].client_timeout(self.timeout),
                                      client_id)
        finally:
            transport.close()
        reply.raise_for_code()
        return dict(reply.result)


def package_version() -> str:
    """The installed distribution's version (one source of truth: pyproject.toml)."""
    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return "unknown (not installed)"



def error_line(error: GaltonError) -> str:
    """What went wrong in one line: the wire code for a daemon's refusal, else which side."""
    if isinstance(error, RemoteError):
        return f"{error.code.name} ({int(error.code)}): {error.message}"
    if isinstance(error, DaemonUnreachableError):
        return f"unreachable (client side): {error}"
    if isinstance(error, RequestTimeoutError):
        return f"timed out (client side): {error}"
    if isinstance(error, AccessDeniedError):
        return f"access denied (client side): {error}"
    return f"{type(error).__name__}: {error}"


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
        table = Table(title=f"daemon {status.instance}", show_header=False)
        for key, value in asdict(status).items():
            table.add_row(key, f"{value:.4g}" if isinstance(value, float) else str(value))
        console.print(table)
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
