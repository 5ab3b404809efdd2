"""``galton-client hash-password USER``: the users-file line for a password, read unseen.

The line holds ``sha256("galton:" + USER + ":" + password)``, the password Zenoh compares
(galton.protocol.auth): the users file then needs no clear password, but the hash is
password-equivalent for Zenoh, so the file must stay private (docs/SECURITY.md).
"""

from __future__ import annotations

import getpass
import sys
from typing import Annotated

import typer

from galton.client.cli.common import run_guarded
from galton.protocol.auth import validate_user_name, wire_password
from galton.protocol.errors import InvalidArgumentError

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()


def read_password(user: str) -> str:
    """From the terminal without echo, asked twice; from a pipe, its first line."""
    if not sys.stdin.isatty():
        line = sys.stdin.readline().rstrip("\r\n")
        if not line:
            raise InvalidArgumentError("no password on standard input")
        return line
    password = getpass.getpass(f"password for {user}: ")
    if getpass.getpass("the same again: ") != password:
        raise InvalidArgumentError("the two passwords differ; nothing was printed")
    return password


@commands.command("hash-password", rich_help_panel="Network")
def hash_password(
    user: Annotated[str, typer.Argument(help="The user's name, as in the users file.")],
) -> None:
    """Print the ``password_sha256`` line of USER for a daemon's users file; the password is
    read without echo (or from standard input when it is not a terminal)."""
    def line() -> str:
        name = validate_user_name(user)
        return f'password_sha256 = "{wire_password(name, read_password(name))}"'
    typer.echo(run_guarded(line))
