"""galton-client take-control and release-control: the daemon's control lease.

Control belongs to a client, and a command's client lives as long as the command: so
``take-control`` holds control while it runs (until Ctrl-C, or for ``--hold`` seconds) and
releases it when it ends, however it ends. ``status`` shows who holds it.
"""

from __future__ import annotations

import json
import threading
from contextlib import suppress
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import JsonOpt, console, emit, with_client

if TYPE_CHECKING:
    from galton.client.sdk.client import Client

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Control"


@commands.command("take-control", rich_help_panel=PANEL)
def take_control(ctx: typer.Context,
                 hold: Annotated[float | None, typer.Option(
                     help="Seconds to hold control, then release it (default: until "
                          "Ctrl-C).", min=0.0)] = None,
                 as_json: JsonOpt = False) -> None:
    """Take control of the daemon and hold it while this command runs: other clients'
    requests that change or step the world are refused (CONTROL_HELD) until it ends.

    With --json, one line {"instance", "controller"} is printed once control is taken."""
    if hold is not None and not 0.0 <= hold <= threading.TIMEOUT_MAX:  # inf, nan, 1e300
        raise typer.BadParameter(
            f"{hold:g} is no number of seconds to wait (at most {threading.TIMEOUT_MAX:.3g}); "
            "leave --hold out to hold control until Ctrl-C", param_hint="'--hold'")

    def hold_control(client: Client) -> None:
        client.take_control()
        if as_json:
            typer.echo(json.dumps({"instance": client.instance, "controller": client.client_id}))
        else:
            until = "Ctrl-C" if hold is None else f"{hold:g} s"
            console.print(f"holding control of {client.instance} as {client.client_id} "
                          f"(until {until})", markup=False)
        with suppress(KeyboardInterrupt):
            threading.Event().wait(hold)  # nothing sets it: a wait that Ctrl-C ends
        client.release_control()
        if not as_json:
            console.print(f"released control of {client.instance}", markup=False)
    with_client(ctx, hold_control)


@commands.command("release-control", rich_help_panel=PANEL)
def release_control(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Release control held by this command's client. Another process's control is its
    own: the daemon refuses (CONTROL_HELD, naming the holder), and the lease ends when that
    process ends. With nobody holding control there is nothing to do."""

    def release(client: Client) -> bool:
        return client.release_control()
    released = with_client(ctx, release)
    emit({"released": released}, as_json, lambda: console.print(
        "released control" if released else "nobody held control", markup=False))
