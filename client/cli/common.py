"""galton-client: find, watch and drive galton daemons; run the Galton benchmark.

Every operation of the wire protocol has a command; "call OP JSON" sends any request as is.
Lists: several entity names are separate arguments (delete a b c); a list given to one
option is comma-separated in that one value (--pos 0,0,1 or --read a,b). Errors print one
line naming the wire code and exit 1; bad command lines exit 2 before anything is sent.
"""

from __future__ import annotations

import inspect
import json
import math
import os
import re
import sys
from collections.abc import Callable
from dataclasses import asdict
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer
from rich import box
from rich.console import Console
from rich.markup import escape
from rich.table import Table

from galton.client.transport.credentials import Credentials, resolve_credentials
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
    """A console whose tables keep every character at 80 columns: the first column (the
    names a user types back: joints, links, parameters) as wide as its longest cell (up to
    KEY_WIDTH), the others folded onto more lines instead of cut to "…", light borders."""

    def print(self, *objects: Any, **kwargs: Any) -> None:
        for item in objects:
            if isinstance(item, Table):
                readable(item)
        super().print(*objects, **kwargs)


KEY_WIDTH = 40


def readable(table: Table) -> None:
    table.box = box.SIMPLE_HEAD
    for index, column in enumerate(table.columns):
        column.overflow = "fold"
        if index == 0:
            cells = [len(str(cell)) for cell in column.cells]
            column.min_width = min(KEY_WIDTH, max([len(str(column.header)), *cells]))


app = typer.Typer(add_completion=False, help=__doc__, no_args_is_help=True)
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


def package_version() -> str:
    """The installed distribution's version (one source of truth: pyproject.toml)."""
    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return "unknown (not installed)"


def print_version(wanted: bool) -> None:
    if wanted:
        typer.echo(f"galton-client {package_version()}")
        raise typer.Exit(0)


@app.callback()
def main_options(
    ctx: typer.Context,
    connect: Annotated[list[str] | None, typer.Option(
        help="Zenoh endpoint(s) of daemons, comma-separated (default tcp/127.0.0.1:7460), "
             "or one daemon's ZeroMQ endpoint: zmq+ipc:///path or zmq+tcp://HOST:PORT.")
    ] = None,
    instance: Annotated[str, typer.Option(help="Daemon instance to control.")] = "galton",
    timeout: Annotated[float, typer.Option(
        help="Seconds to wait for a reply (steps and rebuilds wait longer).")] = 5.0,
    user: Annotated[str | None, typer.Option(
        help="User name for a daemon started with --users (else GALTON_USER).",
        rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    password_file: Annotated[Path | None, typer.Option(
        help="A file whose first line is the user's password (else GALTON_PASSWORD; a "
             "GALTON_CREDENTIALS file may hold every credential).", dir_okay=False,
        rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    tls_ca: Annotated[Path | None, typer.Option(
        help="CA certificate (PEM) that signed the daemon's TLS certificate.",
        dir_okay=False, rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    tls_cert: Annotated[Path | None, typer.Option(
        help="This client's TLS certificate (PEM), for mutual TLS.", dir_okay=False,
        rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    tls_key: Annotated[Path | None, typer.Option(
        help="The private key (PEM) of --tls-cert.", dir_okay=False,
        rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    zmq_key: Annotated[Path | None, typer.Option(
        help="This client's CURVE key pair (.key_secret) for a daemon's encrypted ZeroMQ "
             "front (else GALTON_ZMQ_KEY).", dir_okay=False,
        rich_help_panel="Credentials (docs/SECURITY.md)")] = None,
    zmq_server_key: Annotated[str | None, typer.Option(
        help="The daemon's CURVE public key: its .key file or the Z85 text (else "
             "GALTON_ZMQ_SERVER_KEY).", rich_help_panel="Credentials (docs/SECURITY.md)")
    ] = None,
    show_version: Annotated[bool, typer.Option(
        "--version", is_eager=True, callback=print_version,
        help="Print the version and exit.")] = False,
) -> None:
    if not math.isfinite(timeout) or timeout <= 0:
        raise typer.BadParameter(f"--timeout must be a number of seconds above 0, got {timeout}")
    credentials = None
    if ctx.invoked_subcommand != "hash-password":
        try:
            credentials = resolve_credentials(user, password_file, tls_ca, tls_cert, tls_key,
                                              os.environ)
        except GaltonError as error:
            raise typer.BadParameter(str(error)) from error
    ctx.obj = Target(connect, instance, timeout, credentials, _zmq_keys(zmq_key, zmq_server_key))


def _zmq_keys(key: Path | None, server_key: str | None) -> ZmqKeys | None:
    """The options' CURVE keys (both or neither), else the environment's."""
    if key is None and server_key is None:
        return None
    if key is None or server_key is None:
        raise typer.BadParameter("--zmq-key and --zmq-server-key go together")
    from galton.client.transport.zmq_keys import ZmqKeys
    try:
        return ZmqKeys.load(key, server_key)
    except GaltonError as error:
        raise typer.BadParameter(str(error)) from error


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


def main() -> None:
    """The console command: every error is one line on stderr, exit code 2 for a bad
    command line (typer's boxed usage text and pydantic's "Value error, " left out)."""
    try:
        code = app(standalone_mode=False)
    except typer.Abort:
        typer.echo("galton-client: aborted", err=True)
        sys.exit(1)
    except typer.TyperException as error:  # click's UsageError and its kin
        sys.exit(usage_error(error))
    sys.exit(code if isinstance(code, int) else 0)


def usage_error(error: typer.TyperException) -> int:
    """Print a command-line error as one line; return its exit code."""
    message = " ".join(str(getattr(error, "format_message", error.__str__)()).split())
    message = message.replace("Value error, ", "")
    context = getattr(error, "ctx", None)
    command = context.command_path if context is not None else "galton-client"
    typer.echo(f"galton-client: {message} (see '{command} --help')", err=True)
    code: int = getattr(error, "exit_code", 2)
    return code


# Registering every command on ``app`` (each module adds its own):
from galton.client.cli import (  # noqa: E402,F401
    auth,
    bench,
    call,
    check,
    control,
    fuzz,
    joints,
    laws,
    perception,
    report_card,
    router,
    scene,
    states,
    streams,
    time,
    view,
    world,
    worlds,
)
from galton.client.cli import zmq_keys as zmq_keys_commands  # noqa: E402,F401

tidy_help(app)
