"""galton-client play, set-rtf, pause, stop, step, run-until and reset: the world's clock."""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.choices import LIST_HELP, ResetScope, counted, numbers, split_list
from galton.client.cli.common import JsonOpt, show_stamp, show_status, status_call, with_client
from galton.client.cli.joints import joint_states_dict, render_joint_states, show_joint_states
from galton.client.cli.states import show_states, states_dict
from galton.client.cli.worlds import WorldOpt, on_world
from galton.protocol.vocabulary import MAX_RTF

if TYPE_CHECKING:
    from galton.client.sdk.client import Client, JointStates, States

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Clock"
Read = Annotated[str | None, typer.Option(
    help=f"Entities whose states the reply carries, read after the last step, {LIST_HELP}.")]
ReadJoints = Annotated[str | None, typer.Option(
    help=f"1-DOF joints whose states the reply carries, read after the last step, "
         f"{LIST_HELP}.")]
Rtf = Annotated[float, typer.Argument(
    help="Target real-time factor (0 = as fast as possible).", min=0.0, max=MAX_RTF,
    show_default=False)]


@commands.command(rich_help_panel=PANEL)
def play(ctx: typer.Context,
         rtf: Annotated[float | None, typer.Option(
             help="Target real-time factor (0 = as fast as possible; default: the current "
                  "target).", min=0.0, max=MAX_RTF)] = None,
         as_json: JsonOpt = False) -> None:
    """Run the simulation continuously."""
    show_status(status_call(ctx, "play", {} if rtf is None else {"rtf": rtf}), as_json)


@commands.command("set-rtf", rich_help_panel=PANEL)
def set_rtf(ctx: typer.Context, rtf: Rtf, as_json: JsonOpt = False) -> None:
    """Change the target real-time factor, playing or not."""
    show_status(status_call(ctx, "set_rtf", {"rtf": rtf}), as_json)


@commands.command(rich_help_panel=PANEL)
def pause(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Pause the simulation clock (a running step request ends)."""
    show_status(status_call(ctx, "pause"), as_json)


@commands.command(rich_help_panel=PANEL)
def stop(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """Pause and rewind: time to 0, entities back to their created state."""
    show_status(status_call(ctx, "stop"), as_json)


@commands.command(rich_help_panel=PANEL)
def reset(ctx: typer.Context,
          scope: Annotated[ResetScope, typer.Option(
              help="time: clock to 0; state: entities to their created state; spawned: "
                   "remove every entity; all: both removal and clock.")] = "all",
          as_json: JsonOpt = False) -> None:
    """Reset time, states, spawned entities, or all (parameters are kept). A playing or
    paused world stays so (a paused world at time 0 is not "stopped": stop rewinds and
    stops)."""
    show_status(status_call(ctx, "reset", {"scope": str(scope)}), as_json)


def read_names(read: str | None, where: str = "--read") -> list[str] | None:
    return None if read is None else split_list(read, where)


def show_reading(states: States | None, joints: JointStates | None, as_json: bool) -> None:
    """What a reading step brought back: bodies, joints, or both (JSON: the states' map with
    the joints' under "joints")."""
    if joints is None:
        if states is not None:
            show_states(states, as_json)
    elif states is None:
        show_joint_states(joints, as_json)
    elif as_json:
        typer.echo(json.dumps({**states_dict(states), "joints": joint_states_dict(joints)},
                              indent=2))
    else:
        show_states(states, False)
        render_joint_states(joints)


def read_step(client: Client, count: int, names: list[str] | None,
              joints: list[str] | None) -> tuple[States | None, JointStates | None]:
    if joints is None:
        return client.step_and_read(count, names or []), None
    if names is None:
        return None, client.step_and_read_joints(count, joints)
    return client.step_and_read_both(count, names, joints)


@commands.command(rich_help_panel=PANEL)
def step(ctx: typer.Context,
         count: Annotated[int, typer.Argument(help="Steps to advance.", min=1)] = 1,
         read: Read = None,
         read_joints: ReadJoints = None,
         world: WorldOpt = None,
         as_json: JsonOpt = False) -> None:
    """Advance exactly COUNT steps (paused or stopped; a side world moves only so);
    returns when they are done."""
    names, joints = read_names(read), read_names(read_joints, "--read-joints")
    if names is None and joints is None:
        stamp = with_client(ctx, lambda c: on_world(c, world).step(count))
        show_stamp(f"{counted(count, 'step', 'steps')} done", stamp, as_json, steps=count)
        return
    show_reading(*with_client(ctx, lambda c: read_step(on_world(c, world), count, names,
                                                        joints)), as_json)


def rest_rule(text: str) -> tuple[float, float]:
    """SPEED,EVERY: the speed (m/s) under which a body is at rest, looked at every EVERY s."""
    values = numbers(text, "--until-rest")
    if len(values) != 2:
        raise typer.BadParameter(f"--until-rest takes SPEED,EVERY, got {text!r}")
    return values[0], values[1]


@commands.command("run-until", rich_help_panel=PANEL)
def run_until(
    ctx: typer.Context,
    sim_time: Annotated[float, typer.Argument(help="Sim time to reach, s.",
                                              show_default=False)],
    read: Read = None,
    read_joints: ReadJoints = None,
    until_rest: Annotated[str | None, typer.Option(
        help="SPEED,EVERY: stop early once every --read body moves slower than SPEED m/s, "
             "looked at every EVERY s of sim time.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Step until the sim time reaches SIM_TIME (or the --read bodies come to rest)."""
    names, joints = read_names(read), read_names(read_joints, "--read-joints")
    if joints is not None:
        if names is not None or until_rest is not None:
            raise typer.BadParameter("run-until takes --read-joints without --read and "
                                     "--until-rest (step reads bodies and joints at once)")
        show_joint_states(with_client(
            ctx, lambda c: c.run_until_and_read_joints(sim_time, joints)), as_json)
    elif until_rest is not None:
        if names is None:
            raise typer.BadParameter("--until-rest needs --read (the bodies to watch)")
        speed, every = rest_rule(until_rest)
        states, at_rest = with_client(
            ctx, lambda c: c.run_until_rest(sim_time, names, speed, every))
        show_states(states, as_json, at_rest=at_rest)
    elif names is not None:
        show_states(with_client(ctx, lambda c: c.run_until_and_read(sim_time, names)), as_json)
    else:
        stamp = with_client(ctx, lambda c: c.run_until(sim_time))
        show_stamp(f"ran until {sim_time:g} s", stamp, as_json)
