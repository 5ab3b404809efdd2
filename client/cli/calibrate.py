"""galton-client calibrate REC --fit box.friction,ball.restitution: fit the daemon's world
to a recording (docs/protocol.md, "calibrate"); the recording's first sample sets the
states the predictions start from, and the world changes only with --apply."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from galton.client.cli.choices import split_list
from galton.client.cli.common import JsonOpt, console, emit, with_client

if TYPE_CHECKING:
    from galton.client.sdk.calibration import CalibrationResult
    from galton.client.sdk.client import Client

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Worlds and snapshots"


def parse_bounds(text: str | None) -> dict[str, tuple[float, float]]:
    """``box.friction=0.05:1.5,ball.restitution=0:0.95`` as {name: (low, high)}."""
    found: dict[str, tuple[float, float]] = {}
    for item in split_list(text, "--bounds") if text else []:
        name, _, span = item.partition("=")
        low, colon, high = span.partition(":")
        try:
            found[name.strip()] = (float(low), float(high))
        except ValueError:
            colon = ""
        if not name or not colon:
            raise typer.BadParameter(f"--bounds takes NAME=LOW:HIGH items, got {item!r}")
    return found


@commands.command(rich_help_panel=PANEL)
def calibrate(
    ctx: typer.Context,
    recording: Annotated[Path, typer.Argument(help="A recording (.npz) of galton-client "
                                              "record.", show_default=False)],
    fit: Annotated[str, typer.Option(help="Parameters to fit: BODY.PROPERTY (friction, "
                                     "restitution, mass), JOINT.damping or gravity, "
                                     "comma-separated.")],
    bounds: Annotated[str | None, typer.Option(help="NAME=LOW:HIGH,... (default per "
                                               "property: friction 0:2, restitution "
                                               "0:0.95, mass 0.01:100, damping 0:10, "
                                               "gravity 0:20).")]
    = None,
    apply: Annotated[bool, typer.Option("--apply", help="Set the fitted values in the "
                                        "world.")] = False,
    max_predictions: Annotated[int, typer.Option(help="At most this many predictions.")]
    = 200,
    world: Annotated[str | None, typer.Option(help="The world to fit; default: the live "
                                              "one.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Fit body and world parameters so the world's predictions match a recording."""
    # numpy and the SDK load only when this command runs (the CLI's start stays light).
    from galton.client.sdk.calibration import bounds_for, observed_in
    from galton.client.sdk.recording import Recording

    names = split_list(fit, "--fit")
    try:
        chosen = bounds_for(names, parse_bounds(bounds))
        seen = observed_in(Recording.load(recording))
    except Exception as error:
        raise typer.BadParameter(str(error)) from error

    def run(client: Client) -> CalibrationResult:
        target = client if world is None else client.world(world)
        return target.calibrate(chosen, seen.names, seen.times, seen.poses, apply=apply,
                                max_predictions=max_predictions)
    result = with_client(ctx, run)

    def render() -> None:
        table = Table("parameter", "fitted", "interval")
        for name, value in result.fitted.items():
            low, high = result.intervals[name]
            table.add_row(name, f"{value:.4g}", f"[{low:.4g}, {high:.4g}]")
        console.print(table)
        console.print(f"position error {result.error_before:.4g} m -> "
                      f"{result.error_after:.4g} m after {result.predictions} predictions"
                      f"{' (applied)' if result.applied else ''}")
    emit(result.to_json(), as_json, render)
