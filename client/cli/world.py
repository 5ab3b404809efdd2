"""galton-client daemons, status, capabilities, load-world and params: daemons and worlds."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import Engine, assignments
from galton.client.cli.common import (
    JsonOpt,
    Target,
    console,
    emit,
    run_guarded,
    show_status,
    status_call,
    with_client,
)

if TYPE_CHECKING:
    from galton.client.sdk.client import Client
    from galton.protocol import Capabilities

if TYPE_CHECKING:
    pass

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "World"
Assignments = Annotated[list[str] | None, typer.Argument(
    help="NAME=VALUE pairs, VALUE read as JSON (gravity=[0,0,-9.81]).", metavar="NAME=VALUE...",
    show_default=False)]


@commands.command(rich_help_panel=PANEL)
def daemons(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """List the daemons reachable through --connect, with instance, engine, state, host
    and ZeroMQ endpoints."""
    from galton.client.transport.discovery import discover_at
    target: Target = ctx.obj
    found = run_guarded(lambda: discover_at(target.connect, target.timeout,
                                            target.credentials))

    def render() -> None:
        zmq = any(d.zmq for d in found)  # a ZeroMQ column only where a daemon serves one
        table = Table("instance", "engine", "state", "sim time (s)", "entities", "host",
                      *(["ZeroMQ"] if zmq else []))
        for d in found:
            table.add_row(d.instance, d.engine, d.state, f"{d.sim_time:.3f}",
                          str(d.entity_count), host_line(d.host),
                          *([", ".join(d.zmq) or "–"] if zmq else []))
        console.print(table if found else "no daemon found")
    emit([d.to_dict() for d in found], as_json, render)


commands.command("ls", hidden=True)(daemons)  # the old name: one command, two names


def host_line(host: dict[str, Any]) -> str:
    """A daemon's machine in a few words: hostname, CPU model, logical cores."""
    if not host:
        return "–"
    return f"{host.get('hostname', '?')}: {host.get('cpu_model', '?')}, " \
           f"{host.get('logical_cores', '?')} cores"


@commands.command(rich_help_panel=PANEL)
def status(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Show the simulation state and clock of one daemon."""
    show_status(status_call(ctx, "status"), as_json)


@commands.command(rich_help_panel=PANEL)
def capabilities(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Show what the engine can do: shapes, model formats, features and parameters."""
    found = with_client(ctx, lambda c: c.capabilities())
    emit(found.to_wire(), as_json, lambda: render_capabilities(found))


def render_capabilities(found: Capabilities) -> None:
    table = Table(title=f"{found.engine} {found.engine_version}", show_header=False)
    table.add_row("protocol version", str(found.protocol_version))
    for label, items in (("body shapes", found.body_shapes),
                         ("model formats", found.model_formats), ("features", found.features),
                         ("engines available", found.engines_available)):
        table.add_row(label, ", ".join(items))
    console.print(table)
    params = Table("parameter", "default", "unit", "meaning", title="parameters")
    for name, info in sorted(found.params.items()):
        params.add_row(name, json.dumps(info.get("default")), str(info.get("unit", "")),
                       str(info.get("doc", "")))
    console.print(params)


@commands.command("load-world", rich_help_panel=PANEL)
def load_world(ctx: typer.Context,
               engine: Annotated[Engine, typer.Argument(help="Engine of the new world.",
                                                        show_default=False)],
               params: Assignments = None,
               as_json: JsonOpt = False) -> None:
    """Replace the world with an empty, stopped one on ENGINE, with default parameters
    (then NAME=VALUE ones), without restarting the daemon."""
    values = assignments(params)
    show_status(with_client(ctx, lambda c: c.load_world(str(engine), values)), as_json)


@commands.command(rich_help_panel=PANEL)
def params(ctx: typer.Context, assign: Assignments = None, as_json: JsonOpt = False) -> None:
    """Show engine parameters with each default and where it comes from (the simulator's
    own set-up, or the daemon's and why), or set some (all or none) and show them after."""
    updates = assignments(assign)

    def read(c: Client) -> tuple[dict[str, Any], Capabilities]:
        return (c.set_params(updates) if updates else c.get_params()), c.capabilities()
    values, found = with_client(ctx, read)

    def render() -> None:
        table = Table("parameter", "value", "default: where it comes from",
                      title=f"{found.engine} {found.engine_version} (* : not the default)")
        for key, value in sorted(values.items()):
            spec = found.params.get(key, {})
            changed = "" if value == spec.get("default") else " *"
            table.add_row(key, json.dumps(value) + changed,
                          f"{json.dumps(spec.get('default'))}: {spec.get('source', '?')}")
        console.print(table)
    emit(values, as_json, render)
