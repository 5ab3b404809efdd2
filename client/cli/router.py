"""``galton-client router``: a Zenoh router, so daemons and clients on several machines meet.

Daemons on each computer ``--connect`` to it, and so do clients; it routes their queries,
telemetry and liveliness tokens. zenoh-python opens a session in router mode itself, so no
separate ``zenohd`` (nor any home-made broker) is needed.
"""

from __future__ import annotations

import json
import signal
import threading
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, Annotated

import typer

if TYPE_CHECKING:
    import zenoh

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()


DEFAULT_ROUTER_LISTEN = "tcp/127.0.0.1:7447"
READY_PREFIX = "galton-client router ready:"


def router_config(listen: list[str], connect: list[str], multicast: bool,
                  config_file: Path | None = None) -> zenoh.Config:
    """A router listening on ``listen``, else on the config file's endpoints, else on
    DEFAULT_ROUTER_LISTEN (never Zenoh's own default: every interface), joined to other
    routers at ``connect``; a Zenoh config file (TLS, access control) may set the rest."""
    import zenoh
    config = zenoh.Config.from_file(str(config_file)) if config_file else zenoh.Config()
    silent = config.get_json("listen/endpoints") == zenoh.Config().get_json("listen/endpoints")
    config.insert_json5("mode", json.dumps("router"))
    if listen or silent:
        config.insert_json5("listen/endpoints", json.dumps(listen or [DEFAULT_ROUTER_LISTEN]))
    if connect:
        config.insert_json5("connect/endpoints", json.dumps(connect))
    config.insert_json5("scouting/multicast/enabled", json.dumps(multicast))
    return config


def wait_for_stop() -> None:
    """Block until SIGINT or SIGTERM."""
    stop = threading.Event()

    def on_signal(signum: int, frame: FrameType | None) -> None:
        stop.set()
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, on_signal)
    stop.wait()


@commands.command(rich_help_panel="Network")
def router(
    listen: Annotated[list[str] | None, typer.Option(
        help="Endpoint to listen on (repeatable); e.g. tcp/0.0.0.0:7447 for other machines. "
             f"Default {DEFAULT_ROUTER_LISTEN}.")] = None,
    connect: Annotated[list[str] | None, typer.Option(
        help="Another router to join (repeatable).")] = None,
    multicast: Annotated[bool, typer.Option(
        help="Let Zenoh's multicast scouting find peers on the LAN.")] = False,
    zenoh_config: Annotated[Path | None, typer.Option(
        help="A Zenoh JSON5 config file (e.g. TLS endpoints, access control); the options "
             "above still override it.", exists=True, dir_okay=False)] = None,
) -> None:
    """Run a Zenoh router until Ctrl-C or SIGTERM: start daemons with `galton-daemon
    --connect tcp/HOST:7447`, and point clients at the same endpoint."""
    import zenoh

    from galton.client.transport.session import close_session
    endpoints = listen or []
    try:
        config = router_config(endpoints, connect or [], multicast, zenoh_config)
        endpoints = endpoints or _listed(config)
        session = zenoh.open(config)
    except zenoh.ZError as error:
        typer.echo(f"galton-client: the router could not start on "
                   f"{', '.join(endpoints) or zenoh_config}: {error}", err=True)
        raise typer.Exit(1) from error
    try:
        typer.echo(f"{READY_PREFIX} listen={','.join(endpoints) or 'from the config'} "
                   f"zid={session.zid()}")
        wait_for_stop()
    finally:
        close_session(session)


def _listed(config: zenoh.Config) -> list[str]:
    """The endpoints the router will listen on, when the config names them as a list."""
    endpoints = json.loads(config.get_json("listen/endpoints"))
    return [str(e) for e in endpoints] if isinstance(endpoints, list) else []
