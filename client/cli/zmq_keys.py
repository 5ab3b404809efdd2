"""``galton-client zmq-keys DIR``: a CURVE key pair for the ZeroMQ front, made by pyzmq.

For a daemon: ``galton-daemon --zmq-key DIR/NAME.key_secret``; its clients get
``DIR/NAME.key`` (the public half) as ``--zmq-server-key``. For a client: ``--zmq-key
DIR/NAME.key_secret``, and the printed line goes in the daemon's users file.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import run_guarded
from galton.protocol.errors import InvalidArgumentError

if TYPE_CHECKING:
    pass

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()


@commands.command("zmq-keys", rich_help_panel="Network")
def zmq_keys(
    folder: Annotated[Path, typer.Argument(help="Folder to write NAME.key and "
                                                "NAME.key_secret in (made if missing).")],
    name: Annotated[str, typer.Option(help="The files' name.")] = "galton",
) -> None:
    """Write a CURVE key pair (the secret file readable by its owner only) and print the
    users-file line of its public key."""
    import zmq.auth
    def make() -> str:
        folder.mkdir(parents=True, exist_ok=True)
        for made in (folder / f"{name}.key", folder / f"{name}.key_secret"):
            if made.exists():  # NAME.key may be the daemon's public key, kept there
                raise InvalidArgumentError(
                    f"{made} exists: nothing was overwritten (give another --name)")
        public_file, secret_file_made = zmq.auth.create_certificates(str(folder), name)
        os.chmod(secret_file_made, 0o600)
        public, _ = zmq.auth.load_certificate(public_file)
        return (f"wrote {public_file} and {secret_file_made}\n"
                f'zmq_public_key = "{public.decode()}"')
    typer.echo(run_guarded(make))
