"""galton-client joints, get-joints, set-joints, joint-targets, wrench and clear-wrenches.

The joints of loaded models and the wrenches on bodies (docs/protocol.md, "joints" to
"clear_wrenches"). Per-joint numbers are comma-separated, one per joint or one for all;
force, torque and point rows are x,y,z per body or one for all. Each command also answers to
its operation's name with dashes (get-joint-states, set-joint-states, set-joint-targets,
apply-wrench), hidden from the command list.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import LIST_HELP, TargetMode, counted, numbers, rows
from galton.client.cli.common import JsonOpt, console, emit, show_stamp, with_client
from galton.client.cli.states import NamesArg

if TYPE_CHECKING:
    from galton.protocol import JointInfo

if TYPE_CHECKING:
    import numpy as np

    from galton.client.sdk.values import JointStates

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Joints"
JointNamesArg = Annotated[list[str], typer.Argument(
    help="Joint names, as separate arguments.", show_default=False)]
SomeJoints = Annotated[list[str] | None, typer.Argument(
    help="Joint names, as separate arguments; none: every joint.", show_default=False)]
PER_JOINT = f"{LIST_HELP}, one per joint or one for all"


def joint_values(text: str, count: int, where: str) -> np.ndarray:
    """One number per joint from one option value; one number alone is given to all."""
    import numpy as np
    values = numbers(text, where)
    if len(values) == 1:
        return np.full(count, values[0])
    if len(values) != count:
        raise typer.BadParameter(f"{where} needs one number per joint ({count}), or one for "
                                 f"all; got {len(values)}")
    return np.asarray(values, dtype=float)


def _limits(joint: JointInfo) -> str:
    if joint.lower is None and joint.upper is None:
        return "–"
    low = "-inf" if joint.lower is None else f"{joint.lower:.4g}"
    return f"{low} .. {'inf' if joint.upper is None else f'{joint.upper:.4g}'}"


def show_joints(found: list[JointInfo], as_json: bool) -> None:
    """A table of the joints (JSON: every field, model and file limits included)."""
    def render() -> None:
        table = Table("joint", "type", "parent → child", "axis", "limits", "damping", "mode")
        for j in found:
            table.add_row(j.name, j.type, f"{j.parent or '(world)'} → {j.child}",
                          ",".join(f"{a:g}" for a in j.axis), _limits(j), f"{j.damping:.4g}",
                          j.mode)
        console.print(table if found else "no joint")
    emit([j.to_wire() for j in found], as_json, render)


def joint_states_dict(states: JointStates) -> dict[str, Any]:
    """Joint states as plain JSON values: one number per joint in each list."""
    return {"step": states.step, "sim_time": states.sim_time, "names": list(states.names),
            "positions": states.positions.tolist(), "velocities": states.velocities.tolist(),
            "efforts": states.efforts.tolist()}


def render_joint_states(states: JointStates) -> None:
    table = Table("joint", "position (rad | m)", "velocity (rad/s | m/s)",
                  "effort (N·m | N)",
                  title=f"step {states.step}, sim time {states.sim_time:.4f} s")
    for name, q, qd, tau in zip(states.names, states.positions, states.velocities,
                                states.efforts, strict=True):
        table.add_row(name, f"{q:.6g}", f"{qd:.6g}", f"{tau:.6g}")
    console.print(table)


def show_joint_states(states: JointStates, as_json: bool) -> None:
    emit(joint_states_dict(states), as_json, lambda: render_joint_states(states))


@commands.command(rich_help_panel=PANEL)
def joints(
    ctx: typer.Context,
    names: SomeJoints = None,
    model: Annotated[str | None, typer.Option(
        help="Only this model's joints (its root entity).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """List the joints of loaded models: type, links, axis, limits, damping, target mode."""
    show_joints(with_client(ctx, lambda c: c.joints(model, names or None)), as_json)


@commands.command("get-joints", rich_help_panel=PANEL)
def get_joints(ctx: typer.Context, names: SomeJoints = None, as_json: JsonOpt = False) -> None:
    """Show positions, velocities and applied efforts of 1-DOF joints, in one request."""
    show_joint_states(with_client(ctx, lambda c: c.get_joint_states(names or None)), as_json)


@commands.command("set-joints", rich_help_panel=PANEL)
def set_joints(
    ctx: typer.Context,
    names: JointNamesArg,
    positions: Annotated[str, typer.Option(help=f"Positions (rad or m), {PER_JOINT}.",
                                           show_default=False)],
    velocities: Annotated[str | None, typer.Option(
        help=f"Velocities (rad/s or m/s), {PER_JOINT}; default: kept.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Teleport joints between steps (one request); without --velocities each keeps its own."""
    count = len(names)
    q = joint_values(positions, count, "--positions")
    qd = None if velocities is None else joint_values(velocities, count, "--velocities")
    stamp = with_client(ctx, lambda c: c.set_joint_states(names, q, qd))
    show_stamp(f"set {counted(count, 'joint', 'joints')}", stamp, as_json, names=names)


@commands.command("joint-targets", rich_help_panel=PANEL)
def joint_targets(
    ctx: typer.Context,
    mode: Annotated[TargetMode, typer.Argument(
        help="position: kp (target - q) - kd q'; velocity: kd (target - q'); effort: target; "
             "none: free.", show_default=False)],
    names: JointNamesArg,
    targets: Annotated[str | None, typer.Option(
        help=f"Targets (rad, rad/s, N·m; m, m/s, N), {PER_JOINT}; needed unless mode none.")
    ] = None,
    kp: Annotated[str | None, typer.Option(help=f"Stiffness, {PER_JOINT}; default 0.")] = None,
    kd: Annotated[str | None, typer.Option(help=f"Damping gain, {PER_JOINT}; default 0.")
                  ] = None,
    max_effort: Annotated[str | None, typer.Option(
        help=f"Effort limit (N·m or N), {PER_JOINT}; default: none (inf).")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Hold a target on joints, applied every step by the engine until changed (one request)."""
    count = len(names)
    given = {key: None if text is None else joint_values(text, count,
                                                         f"--{key.replace('_', '-')}")
             for key, text in (("targets", targets), ("kp", kp), ("kd", kd),
                               ("max_effort", max_effort))}
    stamp = with_client(ctx, lambda c: c.set_joint_targets(names, str(mode), **given))
    show_stamp(f"{mode} target on {counted(count, 'joint', 'joints')}", stamp, as_json,
               names=names, mode=str(mode))


@commands.command(rich_help_panel=PANEL)
def wrench(
    ctx: typer.Context,
    names: NamesArg,
    force: Annotated[str, typer.Option(
        help=f"Force fx,fy,fz (N, world frame) per body or one for all, {LIST_HELP}.")
    ] = "0,0,0",
    torque: Annotated[str, typer.Option(
        help=f"Torque tx,ty,tz (N·m, world frame) per body or one for all, {LIST_HELP}.")
    ] = "0,0,0",
    at: Annotated[str | None, typer.Option(
        "--at", help=f"Where the force acts, x,y,z (world frame) per body or one for all, "
                     f"{LIST_HELP}; default: each centre of mass.")] = None,
    duration: Annotated[float | None, typer.Option(
        help="Seconds of sim time it acts, above 0 (default: until cleared).")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Apply a world-frame force and torque on bodies or links, held every step."""
    import numpy as np
    count = len(names)
    wrenches = np.hstack([rows(force, count, 3, "--force"), rows(torque, count, 3, "--torque")])
    points = None if at is None else rows(at, count, 3, "--at")
    stamp = with_client(ctx, lambda c: c.apply_wrench(names, wrenches, points, duration))
    show_stamp(f"wrench on {counted(count, 'body', 'bodies')}", stamp, as_json, names=names)


@commands.command("clear-wrenches", rich_help_panel=PANEL)
def clear_wrenches(
    ctx: typer.Context,
    names: Annotated[list[str] | None, typer.Argument(
        help="Bodies whose wrench goes; none: every wrench.", show_default=False)] = None,
    as_json: JsonOpt = False,
) -> None:
    """Remove the wrenches of bodies, or every wrench."""
    stamp = with_client(ctx, lambda c: c.clear_wrenches(names or None))
    what = "every wrench" if not names else counted(len(names), "wrench", "wrenches")
    show_stamp(f"cleared {what}", stamp, as_json, names=names or [])


# The operations' own names, for whoever types them (hidden: one command, two names).
for alias, command in (("get-joint-states", get_joints), ("set-joint-states", set_joints),
                       ("set-joint-targets", joint_targets), ("apply-wrench", wrench)):
    commands.command(alias, hidden=True, rich_help_panel=PANEL)(command)
