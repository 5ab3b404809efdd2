"""galton-client get-states, get-bounds and set-states: poses, twists and boxes of named
bodies."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import LIST_HELP, counted, numbers, rows
from galton.client.cli.common import JsonOpt, console, emit, show_stamp, with_client
from galton.protocol import POSE_WIDTH, TWIST_WIDTH

if TYPE_CHECKING:
    import numpy as np

    from galton.client.sdk.client import States
    from galton.client.sdk.values import ShapeInfo

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Scene"
# Entity names as separate arguments, none meaning every entity (get-states, -bounds, -shapes).
EntityNames = Annotated[list[str] | None, typer.Argument(
    help="Entity names, as separate arguments; none: every entity.", show_default=False)]
NamesArg = Annotated[list[str], typer.Argument(
    help="Entity names, as separate arguments.", show_default=False)]


def states_dict(states: States, **extra: Any) -> dict[str, Any]:
    """States as plain JSON values: a list of 7 numbers per pose, 6 per twist."""
    return {**extra, "step": states.step, "sim_time": states.sim_time,
            "names": list(states.names), "poses": states.poses.tolist(),
            "twists": states.twists.tolist()}


def _numbers(row: np.ndarray | tuple[float, ...]) -> str:
    return ", ".join(f"{value:.4g}" for value in row)


def show_states(states: States, as_json: bool, **extra: Any) -> None:
    """A table of positions, orientations and velocities, or the same as JSON."""
    def render() -> None:
        table = Table("name", "position (m)", "orientation (qx, qy, qz, qw)",
                      "velocity (m/s)", "spin (rad/s)",
                      title=f"step {states.step}, sim time {states.sim_time:.4f} s")
        for name, pose, twist in zip(states.names, states.poses, states.twists, strict=True):
            table.add_row(name, _numbers(pose[:3]), _numbers(pose[3:]), _numbers(twist[:3]),
                          _numbers(twist[3:]))
        console.print(table)
        for key, value in extra.items():
            console.print(f"{key}: {value}", markup=False)
    emit(states_dict(states, **extra), as_json, render)


@commands.command("get-states", rich_help_panel=PANEL)
def get_states(
    ctx: typer.Context,
    names: EntityNames = None,
    as_json: JsonOpt = False,
) -> None:
    """Show poses (x y z qx qy qz qw) and world-frame twists of bodies, in one request."""
    states = with_client(ctx, lambda c: c.get_states(names or None))
    show_states(states, as_json)


@commands.command("get-bounds", rich_help_panel=PANEL)
def get_bounds(
    ctx: typer.Context,
    names: EntityNames = None,
    as_json: JsonOpt = False,
) -> None:
    """Show each entity's axis-aligned bounds in the world frame (min and max x y z)."""
    bounds = with_client(ctx, lambda c: c.get_bounds(names or None))

    def render() -> None:
        table = Table("name", "min (m)", "max (m)")
        for name, row in bounds.items():
            table.add_row(name, _numbers(row[:3]), _numbers(row[3:]))
        console.print(table)
    emit({name: row.tolist() for name, row in bounds.items()}, as_json, render)


@commands.command("get-shapes", rich_help_panel=PANEL)
def get_shapes(
    ctx: typer.Context,
    names: EntityNames = None,
    as_json: JsonOpt = False,
) -> None:
    """Show each entity's collision shapes: kind, half sizes, pose in the entity's frame,
    and a mesh's vertex and triangle counts (or that only its box is known)."""
    shapes = with_client(ctx, lambda c: c.get_shapes(names or None))

    def render() -> None:
        table = Table("name", "kind", "half sizes (m)", "pose (x y z qx qy qz qw)", "mesh")
        for name, found in shapes.items():
            for shape in found:
                table.add_row(name, shape.kind, _numbers(shape.size),
                              _numbers(shape.pose), _triangles(shape))
        console.print(table)
    emit({name: [{"kind": s.kind, "size": list(s.size), "pose": s.pose.tolist(),
                  "triangles": _counts(s)} for s in found]
          for name, found in shapes.items()}, as_json, render)


def _counts(shape: ShapeInfo) -> list[int] | None:
    """A mesh's vertex and triangle counts, where they are told."""
    if shape.vertices is None or shape.faces is None:
        return None
    return [len(shape.vertices), len(shape.faces)]


def _triangles(shape: ShapeInfo) -> str:
    counts = _counts(shape)
    if counts is not None:
        return f"{counts[0]} vertices, {counts[1]} triangles"
    return "its box only" if shape.boxed else ""


@commands.command("set-states", rich_help_panel=PANEL)
def set_states(
    ctx: typer.Context,
    names: NamesArg,
    poses: Annotated[str | None, typer.Option(
        help=f"Poses, {LIST_HELP}: x,y,z,qx,qy,qz,qw per body, or x,y,z per body "
             "(unrotated); one pose alone is given to every body.")] = None,
    twists: Annotated[str | None, typer.Option(
        help=f"Twists, {LIST_HELP}: vx,vy,vz,wx,wy,wz per body (world frame); one alone is "
             "given to every body.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Teleport bodies and/or set their velocities between steps (one request).

    A pose alone keeps each body's twist; a twist alone keeps its pose.
    """
    if poses is None and twists is None:
        raise typer.BadParameter("give --poses and/or --twists")
    pose_rows = None if poses is None else pose_values(poses, len(names), "--poses")
    twist_rows = None if twists is None else rows(twists, len(names), TWIST_WIDTH, "--twists")
    stamp = with_client(ctx, lambda c: c.set_states(names, pose_rows, twist_rows))
    show_stamp(f"set the state of {counted(len(names), 'body', 'bodies')}", stamp, as_json,
               names=names)


def pose_values(text: str, count: int, where: str) -> np.ndarray:
    """Full poses (7 per body), or positions (3 per body) with the identity orientation."""
    import numpy as np
    given = len(numbers(text, where))
    if given in (POSE_WIDTH, count * POSE_WIDTH):
        return rows(text, count, POSE_WIDTH, where)
    if given not in (3, count * 3):
        raise typer.BadParameter(
            f"{where} needs x,y,z,qx,qy,qz,qw or x,y,z per body ({count} bodies), or one "
            f"pose for all; got {given} numbers")
    xyz = rows(text, count, 3, where)
    poses = np.zeros((count, POSE_WIDTH))
    poses[:, :3] = xyz
    poses[:, 6] = 1.0
    return poses
