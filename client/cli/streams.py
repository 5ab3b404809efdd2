"""galton-client watch and events: a daemon's telemetry and event streams, live."""

from __future__ import annotations

import json
import queue
import sys
from collections.abc import Callable
from dataclasses import asdict
from typing import TYPE_CHECKING, Annotated, Any

import typer

from galton.client.cli.common import JsonOpt, Target, console, with_client

if TYPE_CHECKING:
    from galton.protocol import Telemetry

if TYPE_CHECKING:
    from galton.client.sdk.client import Client

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Streams"
Count = Annotated[int, typer.Option(help="Stop after N samples (0 = run until Ctrl-C).",
                                    min=0)]


@commands.command(rich_help_panel=PANEL)
def watch(ctx: typer.Context, count: Count = 0, as_json: JsonOpt = False) -> None:
    """Print live telemetry, a line per world each period: sim time, RTF, CPU and memory
    (JSON: one object a line)."""
    target: Target = ctx.obj

    def go(client: Client) -> None:
        with client.telemetry(timeout=max(target.timeout, 2.0)) as stream:
            for seen, sample in enumerate(stream, start=1):
                print_telemetry(sample, as_json)
                if count and seen >= count:
                    return
    until_interrupted(ctx, go)


def print_telemetry(sample: Telemetry, as_json: bool) -> None:
    if as_json:
        typer.echo(json.dumps(asdict(sample)))
        sys.stdout.flush()
        return
    console.print(
        f"#{sample.seq:<6} {sample.world} {sample.state:<8} t={sample.sim_time:10.3f}s "
        f"step={sample.step:<9} "
        f"rtf={sample.rtf:7.3f} (target {sample.target_rtf:g}) n={sample.entity_count:<5} "
        f"cpu={sample.cpu_percent:5.1f}% rss={sample.rss_bytes / 2**20:7.1f} MiB",
        markup=False)


@commands.command(rich_help_panel=PANEL)
def events(ctx: typer.Context,
           count: Annotated[int, typer.Option(
               help="Stop after N events (0 = run until Ctrl-C).", min=0)] = 0,
           as_json: JsonOpt = False) -> None:
    """Print the daemon's events as they come: state changes, scene changes, physics
    errors, abandoned step requests (JSON: one object a line).

    A line on stderr says when the subscription is in place.
    """
    received: queue.SimpleQueue[dict[str, Any]] = queue.SimpleQueue()

    def go(client: Client) -> None:
        with client.on_event(received.put):
            typer.echo(f"listening to the events of {client.instance}", err=True)
            for seen in range(1, sys.maxsize):
                print_event(received.get(), as_json)
                if count and seen >= count:
                    return
    until_interrupted(ctx, go)


def print_event(event: dict[str, Any], as_json: bool) -> None:
    if as_json:
        typer.echo(json.dumps(event, default=str))
        sys.stdout.flush()
        return
    fields = " ".join(f"{key}={value}" for key, value in event.items()
                      if key not in ("seq", "kind", "instance"))
    console.print(f"#{event.get('seq', '?'):<6} {event.get('kind', '?'):<14} {fields}",
                  markup=False)


def until_interrupted(ctx: typer.Context, go: Callable[[Client], None]) -> None:
    """Run a streaming command until it ends or the user presses Ctrl-C (no traceback)."""
    try:
        with_client(ctx, go)
    except KeyboardInterrupt:
        return
