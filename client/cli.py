"""``galton-client``: find, watch and drive galton daemons; run the Galton benchmark."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable
from dataclasses import asdict
from typing import Annotated, Any, TypeVar

import typer
from rich.console import Console
from rich.table import Table

from galton.client.discovery import discover_at
from galton.client.sdk import Client, body_group
from galton.protocol import GaltonError, SimStatus, Telemetry

app = typer.Typer(add_completion=False, help=__doc__, no_args_is_help=True)
console = Console()
T = TypeVar("T")

JsonOpt = Annotated[bool, typer.Option("--json", help="Print JSON for scripts.")]


class Target:
    """Where the global options point: endpoints, instance, timeout."""

    def __init__(self, connect: list[str] | None, instance: str, timeout: float) -> None:
        self.connect = connect
        self.instance = instance
        self.timeout = timeout

    def client(self) -> Client:
        return Client(self.instance, self.connect, timeout=self.timeout)


@app.callback()
def main_options(
    ctx: typer.Context,
    connect: Annotated[list[str] | None, typer.Option(
        help="Zenoh endpoint(s) of daemons (repeatable or comma-separated); default "
             "tcp/127.0.0.1:7460.")] = None,
    instance: Annotated[str, typer.Option(help="Daemon instance to control.")] = "galton",
    timeout: Annotated[float, typer.Option(help="Seconds to wait for a reply.")] = 5.0,
) -> None:
    ctx.obj = Target(connect, instance, timeout)


def run_guarded(action: Callable[[], T]) -> T:
    """Turn any galton error into one clear line on stderr and exit code 1."""
    try:
        return action()
    except GaltonError as error:
        typer.echo(f"galton-client: {type(error).__name__}: {error}", err=True)
        raise typer.Exit(1) from error


def emit(data: Any, as_json: bool, render: Callable[[], None]) -> None:
    if as_json:
        typer.echo(json.dumps(data, indent=2, default=str))
    else:
        render()


def with_client(ctx: typer.Context, action: Callable[[Client], T]) -> T:
    def go() -> T:
        with ctx.obj.client() as client:
            return action(client)
    return run_guarded(go)


def show_status(status: SimStatus, as_json: bool) -> None:
    def render() -> None:
        table = Table(title=f"daemon {status.instance}", show_header=False)
        for key, value in asdict(status).items():
            table.add_row(key, f"{value:.4g}" if isinstance(value, float) else str(value))
        console.print(table)
    emit(asdict(status), as_json, render)


@app.command("ls")
def list_daemons(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """List the daemons found, with instance, engine and state."""
    found = run_guarded(lambda: discover_at(ctx.obj.connect, ctx.obj.timeout))

    def render() -> None:
        table = Table("instance", "engine", "state", "sim time (s)", "entities")
        for d in found:
            table.add_row(d.instance, d.engine, d.state, f"{d.sim_time:.3f}",
                          str(d.entity_count))
        console.print(table if found else "no daemon found")
    emit([d.to_dict() for d in found], as_json, render)


@app.command()
def status(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Show the simulation state and clock of one daemon."""
    show_status(with_client(ctx, lambda c: c.status()), as_json)


@app.command()
def watch(ctx: typer.Context,
          count: Annotated[int, typer.Option(help="Stop after N samples (0 = forever).")] = 0,
          as_json: JsonOpt = False) -> None:
    """Print live telemetry: sim time, RTF, CPU and memory."""
    def go(client: Client) -> None:
        with client.telemetry(timeout=max(ctx.obj.timeout, 2.0)) as stream:
            for seen, sample in enumerate(stream, start=1):
                print_telemetry(sample, as_json)
                if count and seen >= count:
                    return
    try:
        with_client(ctx, go)
    except KeyboardInterrupt:
        return


def print_telemetry(sample: Telemetry, as_json: bool) -> None:
    if as_json:
        typer.echo(json.dumps(asdict(sample)))
        sys.stdout.flush()
        return
    console.print(
        f"#{sample.seq:<6} {sample.state:<8} t={sample.sim_time:10.3f}s step={sample.step:<9} "
        f"rtf={sample.rtf:7.3f} (target {sample.target_rtf:g}) n={sample.entity_count:<5} "
        f"cpu={sample.cpu_percent:5.1f}% rss={sample.rss_bytes / 2**20:7.1f} MiB")


def _floats(text: str, where: str) -> list[float]:
    try:
        return [float(v) for v in text.split(",")]
    except ValueError:
        raise typer.BadParameter(f"{where} must be comma-separated numbers, got {text!r}") \
            from None


@app.command()
def spawn(
    ctx: typer.Context,
    shape: Annotated[str, typer.Argument(help="sphere, box, cylinder, capsule or plane")],
    name: Annotated[str, typer.Option(help="Entity name (with --count: a prefix).")],
    size: Annotated[str, typer.Option(help="Half sizes, e.g. 0.05 (sphere radius).")] = "0.05",
    pos: Annotated[str, typer.Option(help="x,y,z of the first body, m.")] = "0,0,1",
    count: Annotated[int, typer.Option(help="How many bodies (one request).", min=1)] = 1,
    spacing: Annotated[float, typer.Option(help="x spacing between bodies, m.")] = 0.2,
    static: Annotated[bool, typer.Option(help="Fixed in the world.")] = False,
    mass: Annotated[float | None, typer.Option(help="kg (default: density 1000).")] = None,
    friction: Annotated[float | None, typer.Option()] = None,
    restitution: Annotated[float | None, typer.Option()] = None,
    tag: Annotated[list[str] | None, typer.Option(help="Tag (repeatable).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Spawn one body, or COUNT bodies in a row, in a single request."""
    origin = _floats(pos, "--pos")
    positions = [[origin[0] + i * spacing, origin[1], origin[2]] for i in range(count)]
    names = [name] if count == 1 else [f"{name}_{i}" for i in range(count)]
    group = body_group(shape, tuple(_floats(size, "--size")), names, positions, static=static,
                   mass=mass, friction=friction, restitution=restitution,
                   tags=tuple(tag or ()))
    spawned = with_client(ctx, lambda c: c.spawn(group))
    emit({"names": spawned}, as_json, lambda: console.print(f"spawned {len(spawned)} bodies"))


@app.command()
def step(ctx: typer.Context,
         count: Annotated[int, typer.Argument(help="Steps to advance.", min=1)] = 1,
         as_json: JsonOpt = False) -> None:
    """Advance exactly COUNT steps (the daemon must not be playing)."""
    stamp = with_client(ctx, lambda c: c.step(count))
    emit(asdict(stamp), as_json,
         lambda: console.print(f"step {stamp.step}, sim time {stamp.sim_time:.4f} s"))


@app.command()
def play(ctx: typer.Context,
         rtf: Annotated[float | None, typer.Option(
             help="Target real-time factor (0 = as fast as possible).", min=0.0)] = None,
         as_json: JsonOpt = False) -> None:
    """Run the simulation continuously."""
    show_status(with_client(ctx, lambda c: c.play(rtf)), as_json)


@app.command()
def pause(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Pause the simulation clock."""
    show_status(with_client(ctx, lambda c: c.pause()), as_json)


@app.command()
def stop(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Pause and rewind: time to 0, entities back to their created state."""
    show_status(with_client(ctx, lambda c: c.stop()), as_json)


@app.command()
def reset(ctx: typer.Context,
          scope: Annotated[str, typer.Option(help="time, state, spawned or all.")] = "all",
          as_json: JsonOpt = False) -> None:
    """Reset time, states, spawned entities, or all."""
    show_status(with_client(ctx, lambda c: c.reset(scope)), as_json)


@app.command()
def params(ctx: typer.Context,
           assignments: Annotated[list[str] | None, typer.Argument(
               help="NAME=VALUE pairs (VALUE as JSON) to set; none to show.")] = None,
           as_json: JsonOpt = False) -> None:
    """Show or set engine parameters."""
    updates = dict(_assignment(a) for a in assignments or [])
    values = with_client(ctx, lambda c: c.set_params(updates) if updates else c.get_params())

    def render() -> None:
        table = Table("parameter", "value")
        for key, value in sorted(values.items()):
            table.add_row(key, json.dumps(value))
        console.print(table)
    emit(values, as_json, render)


def _assignment(text: str) -> tuple[str, Any]:
    name, sep, raw = text.partition("=")
    if not sep:
        raise typer.BadParameter(f"{text!r} is not NAME=VALUE")
    try:
        return name, json.loads(raw)
    except json.JSONDecodeError:
        return name, raw


def main() -> None:
    app()


# Registering bench, report and fuzz on ``app``:
from galton.client import cli_bench, cli_check, cli_fuzz  # noqa: E402,F401
