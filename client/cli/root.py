"""The CLI's root: its global options (endpoints, instance, timeout, credentials) and the
wrapper that turns every error into one line. ``app.py`` builds the whole CLI on it;
``console.py`` builds a lean one for the commands that only ask a daemon for its clock
(``status``, ``play`` ...), which import none of the other groups (issue 47)."""

from __future__ import annotations

import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import (
    Target,
    help_text,
    package_version,
    tidy_help,
    widen_help_when_piped,
)
from galton.client.transport.credentials import resolve_credentials
from galton.protocol import GaltonError

if TYPE_CHECKING:
    from galton.client.transport.zmq_keys import ZmqKeys


def make_app(groups: tuple[typer.Typer, ...], about: str) -> typer.Typer:
    """A ``galton-client`` with the global options and ``groups``' commands."""
    made = typer.Typer(add_completion=False, help=about, no_args_is_help=True)
    made.callback()(main_options)
    register(made, groups)
    return made


def register(typer_app: typer.Typer, groups: tuple[typer.Typer, ...]) -> None:
    """Add each group's commands to ``typer_app`` at its top level (no group name), their
    docstrings made help text."""
    typer_app.info.help = help_text(str(typer_app.info.help or ""))
    for group in groups:
        tidy_help(group)
        typer_app.add_typer(group)


def print_version(wanted: bool) -> None:
    if wanted:
        typer.echo(f"galton-client {package_version()}")
        raise typer.Exit(0)


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


def run(app: typer.Typer) -> None:
    """The console command: every error is one line on stderr, exit code 2 for a bad
    command line (typer's boxed usage text and pydantic's "Value error, " left out)."""
    widen_help_when_piped()
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
    option = getattr(error, "option_name", None)
    if isinstance(option, str) and _is_number(option):
        # "No such option: -1": a negative number where an argument goes
        message = (f"{option} is read as an option, not a number: put -- before a negative "
                   f"argument ({command} -- {option})")
    typer.echo(f"galton-client: {message} (see '{command} --help')", err=True)
    code: int = getattr(error, "exit_code", 2)
    return code


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
