"""galton-client worlds, create-world, fork-world, delete-world, snapshot, restore,
snapshots, delete-snapshot, predict and compare: running ahead of reality (docs/protocol.md,
"Worlds" to "compare"). Commands that act on one world take --world (default: the live
one). ``worlds`` also answers to list-worlds, hidden from the command list.
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.choices import LIST_HELP, Engine, assignments, rows, split_list
from galton.client.cli.cluster import RayActorsOpt, RayCpusOpt, ray_predict
from galton.client.cli.common import JsonOpt, console, emit, with_client
from galton.client.cli.states import NamesArg, pose_values
from galton.protocol import TWIST_WIDTH

if TYPE_CHECKING:
    from galton.client.sdk.client import Client
    from galton.client.sdk.values import Comparison, Prediction, SnapshotInfo, WorldInfo

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

PANEL = "Worlds and snapshots"
WorldOpt = Annotated[str | None, typer.Option(
    "--world", help="The world to act on; default: the live one.")]
SlotArg = Annotated[str, typer.Argument(help="The snapshot slot's name.", show_default=False)]
WorldArg = Annotated[str, typer.Argument(help="The world's name.", show_default=False)]


def on_world(client: Client, world: str | None) -> Client:
    return client if world is None else client.world(world)


def show_worlds(found: list[WorldInfo], as_json: bool) -> None:
    def render() -> None:
        table = Table("world", "live", "engine", "state", "step", "sim time (s)", "entities",
                      "faulted")
        for w in found:
            table.add_row(w.name, "yes" if w.live else "", w.engine, w.state, str(w.step),
                          f"{w.sim_time:.4f}", str(w.entity_count), "yes" if w.faulted else "")
        console.print(table)
    emit([asdict(w) for w in found], as_json, render)


@commands.command(rich_help_panel=PANEL)
def worlds(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """List the daemon's worlds: the live one first, then the side worlds."""
    show_worlds(with_client(ctx, lambda c: c.list_worlds()), as_json)


commands.command("list-worlds", hidden=True)(worlds)  # the operation's name: one command, two names


@commands.command("create-world", rich_help_panel=PANEL)
def create_world(
    ctx: typer.Context, name: WorldArg,
    params: Annotated[list[str] | None, typer.Argument(
        help="NAME=VALUE parameters, VALUE read as JSON.", metavar="NAME=VALUE...",
        show_default=False)] = None,
    engine: Annotated[Engine | None, typer.Option(
        help="Its engine; default: the live world's.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Create an empty side world (it moves only when stepped: step --world NAME)."""
    given = assignments(params)
    made = with_client(ctx, lambda c: c.create_world(
        name, None if engine is None else str(engine), given or None))
    show_worlds([made], as_json)


@commands.command("fork-world", rich_help_panel=PANEL)
def fork_world(
    ctx: typer.Context, name: WorldArg,
    source: Annotated[str | None, typer.Option(
        help="The world to copy; default: the live one.")] = None,
    as_json: JsonOpt = False,
) -> None:
    """Copy a world (scene, state, parameters, targets, clock) under a new name."""
    show_worlds([with_client(ctx, lambda c: c.fork_world(name, source))], as_json)


@commands.command("delete-world", rich_help_panel=PANEL)
def delete_world(ctx: typer.Context, name: WorldArg, as_json: JsonOpt = False) -> None:
    """Delete a side world (the live one cannot be)."""
    with_client(ctx, lambda c: c.delete_world(name))
    emit({"deleted": name}, as_json, lambda: console.print(f"deleted world {name}",
                                                           markup=False))


def snapshot_dict(info: SnapshotInfo) -> dict[str, Any]:
    return {key: value for key, value in asdict(info).items() if key != "blob"}


def show_snapshots(found: list[SnapshotInfo], as_json: bool, **extra: Any) -> None:
    def render() -> None:
        table = Table("slot", "world", "engine", "bytes", "step", "sim time (s)", "entities")
        for s in found:
            table.add_row(s.slot or "–", s.world, s.engine, str(s.nbytes), str(s.step),
                          f"{s.sim_time:.4f}", str(s.entity_count))
        console.print(table if found else "no snapshot")
        for key, value in extra.items():
            console.print(f"{key}: {value}", markup=False)
    emit([{**snapshot_dict(s), **extra} for s in found], as_json, render)


@commands.command(rich_help_panel=PANEL)
def snapshot(
    ctx: typer.Context,
    slot: Annotated[str | None, typer.Argument(
        help="Keep it in the daemon under this slot.", show_default=False)] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", help="Save its bytes to this file (restore --file reads it).")] = None,
    world: WorldOpt = None, as_json: JsonOpt = False,
) -> None:
    """Snapshot a world: into a daemon slot, to a file with --out, or both."""
    if slot is None and out is None:
        raise typer.BadParameter("give a SLOT, --out FILE, or both")
    taken = with_client(ctx, lambda c: on_world(c, world).snapshot(slot, blob=out is not None))
    extra: dict[str, Any] = {}
    if out is not None and taken.blob is not None:
        out.write_bytes(taken.blob)
        extra["file"] = str(out)
    show_snapshots([taken], as_json, **extra)


@commands.command(rich_help_panel=PANEL)
def restore(
    ctx: typer.Context,
    slot: Annotated[str | None, typer.Option(help="A daemon slot.")] = None,
    file: Annotated[Path | None, typer.Option(
        "--file", help="A file snapshot --out wrote.", exists=True, dir_okay=False)] = None,
    world: WorldOpt = None, as_json: JsonOpt = False,
) -> None:
    """Put a world back to a snapshot, from --slot or --file (exactly one)."""
    if (slot is None) == (file is None):
        raise typer.BadParameter("give exactly one of --slot or --file")
    blob = None if file is None else file.read_bytes()
    show_worlds([with_client(ctx, lambda c: on_world(c, world).restore(slot, blob))], as_json)


@commands.command(rich_help_panel=PANEL)
def snapshots(ctx: typer.Context, as_json: JsonOpt = False) -> None:
    """List the snapshot slots the daemon keeps."""
    show_snapshots(with_client(ctx, lambda c: c.snapshots()), as_json)


@commands.command("delete-snapshot", rich_help_panel=PANEL)
def delete_snapshot(ctx: typer.Context, slot: SlotArg, as_json: JsonOpt = False) -> None:
    """Delete a snapshot slot."""
    with_client(ctx, lambda c: c.delete_snapshot(slot))
    emit({"deleted": slot}, as_json, lambda: console.print(f"deleted snapshot {slot}",
                                                           markup=False))


def prediction_dict(found: Prediction) -> dict[str, Any]:
    return {"step": found.step, "sim_time": found.sim_time, "steps": found.steps,
            "times": found.times.tolist(), "names": found.names,
            "poses": found.poses.tolist(), "twists": found.twists.tolist(),
            "joint_names": found.joint_names,
            "joint_positions": found.joint_positions.tolist(),
            "joint_velocities": found.joint_velocities.tolist(),
            "futures": found.futures, "seed": found.seed,
            "spread": None if found.spread is None else found.spread.tolist(),
            "scores": None if found.scores is None else found.scores.tolist()}


def render_prediction(found: Prediction) -> None:
    if found.futures > 1:
        render_futures(found)
        return
    table = Table("sim time (s)", *[f"{n} position (m)" for n in found.names],
                  *found.joint_names, title=f"{found.steps} steps ahead of {found.sim_time:.4f} s")
    for k, t in enumerate(found.times):
        cells = [", ".join(f"{v:.4g}" for v in pose[:3]) for pose in found.poses[k]]
        table.add_row(f"{t:.4f}", *cells, *[f"{q:.4g}" for q in found.joint_positions[k]])
    console.print(table)


def render_futures(found: Prediction) -> None:
    """Many futures: per sample, each body's spread of position across them."""
    table = Table("sim time (s)", *[f"{n} spread (m)" for n in found.names],
                  title=f"{found.futures} futures, {found.steps} steps ahead of "
                        f"{found.sim_time:.4f} s (seed {found.seed})")
    for k, t in enumerate(found.times):
        row = [] if found.spread is None else found.spread[k]
        table.add_row(f"{t:.4f}", *[f"{v:.4g}" for v in row])
    console.print(table)
    if found.scores is not None:
        console.print("scores: " + ", ".join(f"{v:.4g}" for v in found.scores), markup=False)


PERTURB_KEYS = ("position", "orientation", "velocity")


def perturb_values(text: str) -> dict[str, float]:
    """``position=0.001,velocity=0.01`` as predict's perturb map."""
    out: dict[str, float] = {}
    for item in split_list(text, "--perturb"):
        key, sep, value = item.partition("=")
        if not sep or key not in PERTURB_KEYS:
            raise typer.BadParameter(f"{item!r}: give KEY=SIGMA with KEY one of "
                                     f"{', '.join(PERTURB_KEYS)}", param_hint="--perturb")
        try:
            out[key] = float(value)
        except ValueError as exc:
            raise typer.BadParameter(f"{item!r}: {value!r} is not a number",
                                     param_hint="--perturb") from exc
    return out


@commands.command(rich_help_panel=PANEL)
def predict(
    ctx: typer.Context,
    horizon: Annotated[float, typer.Argument(help="Seconds of sim time to run ahead.")],
    every: Annotated[float | None, typer.Option(
        help="Seconds between samples; default: every step.")] = None,
    read: Annotated[str | None, typer.Option(help=f"Bodies to sample, {LIST_HELP}.")] = None,
    read_joints: Annotated[str | None, typer.Option(
        help=f"Joints to sample, {LIST_HELP}.")] = None,
    slot: Annotated[str | None, typer.Option(
        help="Start from this snapshot slot instead of the present.")] = None,
    futures: Annotated[int | None, typer.Option(
        help="Futures to run at once (1-64; with --ray, up to 65,600).")] = None,
    perturb: Annotated[str | None, typer.Option(
        help="Noise on each future's start: position=M,orientation=RAD,velocity=M/S "
             "(standard deviations).")] = None,
    seed: Annotated[int | None, typer.Option(help="The perturbation's seed.")] = None,
    world: WorldOpt = None, as_json: JsonOpt = False,
    ray: Annotated[str | None, typer.Option(
        "--ray", metavar="ADDRESS",
        help="Spread the futures over Ray actors, each restoring the world's snapshot into "
             "a daemon of its own ('local', 'auto', ray://HOST:PORT; the [cluster] "
             "extra): the same futures as one daemon's, bit for bit.")] = None,
    ray_cpus_per_daemon: RayCpusOpt = 1.0,
    ray_actors: RayActorsOpt = None,
) -> None:
    """Run a copy of a world ahead (or many, --futures) and print the sampled trajectories
    (with futures: each body's spread across them); the world is never changed."""
    bodies = None if read is None else split_list(read, "--read")
    joints = None if read_joints is None else split_list(read_joints, "--read-joints")
    noise = None if perturb is None else perturb_values(perturb)
    if ray is not None:
        found, where = with_client(ctx, lambda c: ray_predict(
            on_world(c, world), slot, ray, ray_cpus_per_daemon, ray_actors,
            max(ctx.obj.timeout, 30.0), horizon, futures or 1, perturb=noise, seed=seed,
            every=every, read=bodies, read_joints=joints))
        emit({**prediction_dict(found), "executor": where}, as_json,
             lambda: render_on_ray(found, where))
        return
    found = with_client(ctx, lambda c: on_world(c, world).predict(
        horizon, every, bodies, joints, slot, futures=futures, perturb=noise, seed=seed))
    emit(prediction_dict(found), as_json, lambda: render_prediction(found))


def render_on_ray(found: Prediction, where: dict[str, Any]) -> None:
    render_prediction(found)
    console.print(f"Ran on Ray ({where['address']}): {where['actors']} actor(s) on "
                  f"{where['nodes']} node(s); {len(where['retried'])} batch(es) retried",
                  markup=False)


def render_comparison(found: Comparison) -> None:
    table = Table("name", "position error (m)", "angle error (rad)", "speed error (m/s)",
                  title=f"anomaly score {found.score:.4g} at sim time {found.sim_time:.4f} s")
    speeds = found.speed_errors
    for i, name in enumerate(found.names):
        table.add_row(name, f"{found.position_errors[i]:.4g}", f"{found.angle_errors[i]:.4g}",
                      "–" if speeds is None else f"{speeds[i]:.4g}")
    console.print(table)
    if found.corrected:
        console.print("the bodies were set to the observation")
    if found.streak is not None:
        console.print(f"surprising comparisons in a row: {found.streak}"
                      + ("; a calibration is suggested" if found.suggested else "")
                      + ("; the daemon started it" if found.calibrating else ""))


@commands.command(rich_help_panel=PANEL)
def compare(
    ctx: typer.Context, names: NamesArg,
    poses: Annotated[str, typer.Option(
        help="Observed poses, comma-separated: x,y,z,qx,qy,qz,qw per body, or x,y,z per "
             "body (unrotated: compared with the identity orientation), as set-states "
             "takes them; one alone is every body's.")],
    twists: Annotated[str | None, typer.Option(
        help="Observed twists vx,vy,vz,wx,wy,wz per body, comma-separated.")] = None,
    sigma_position: Annotated[float | None, typer.Option(help="m (default 0.01).")] = None,
    sigma_angle: Annotated[float | None, typer.Option(help="rad (default 0.05).")] = None,
    sigma_speed: Annotated[float | None, typer.Option(help="m/s (default 0.1).")] = None,
    correct: Annotated[bool, typer.Option(
        "--correct", help="Set the bodies to the observation.")] = False,
    trigger: Annotated[str | None, typer.Option(
        help="THRESHOLD:WINDOW: count this comparison toward the world's surprise streak; "
             "WINDOW in a row above THRESHOLD suggest a calibration.")] = None,
    calibrate: Annotated[str | None, typer.Option(
        help="With --trigger: the daemon starts the calibration itself when the streak "
             "reaches WINDOW, fitting these parameters (as calibrate's --fit) to the "
             "streak's observations.")] = None,
    calibrate_bounds: Annotated[str | None, typer.Option(
        help="NAME=LOW:HIGH,... for --calibrate (as calibrate's --bounds).")] = None,
    calibrate_apply: Annotated[bool, typer.Option(
        "--calibrate-apply", help="Set the fitted values in the world.")] = False,
    calibrate_max_predictions: Annotated[int, typer.Option(
        help="At most this many predictions for --calibrate.")] = 200,
    world: WorldOpt = None, as_json: JsonOpt = False,
) -> None:
    """Compare observed poses with a world's: per-body errors and one anomaly score (about 1
    at the sigmas' noise; above 3, a surprise)."""
    pose_rows = pose_values(poses, len(names), "--poses")
    twist_rows = None if twists is None else rows(twists, len(names), TWIST_WIDTH, "--twists")
    watch = None if trigger is None else trigger_value(trigger)
    fit = None if calibrate is None else calibration_value(
        calibrate, calibrate_bounds, calibrate_apply, calibrate_max_predictions)
    if fit is not None and watch is None:
        raise typer.BadParameter("--calibrate starts with a surprise streak: give --trigger",
                                 param_hint="--calibrate")
    found = with_client(ctx, lambda c: on_world(c, world).compare(
        names, pose_rows, twist_rows, sigma_position, sigma_angle, sigma_speed, correct,
        trigger=watch, calibrate=fit))
    emit({"names": found.names, "position_errors": found.position_errors.tolist(),
          "angle_errors": found.angle_errors.tolist(),
          "speed_errors": None if found.speed_errors is None else found.speed_errors.tolist(),
          "score": found.score, "corrected": found.corrected, "step": found.step,
          "sim_time": found.sim_time, "streak": found.streak, "suggested": found.suggested,
          "calibrating": found.calibrating},
         as_json, lambda: render_comparison(found))


def calibration_value(fit: str, bounds: str | None, apply: bool,
                      max_predictions: int) -> dict[str, Any]:
    """--calibrate and its options as the trigger's ``calibrate`` (bounds as calibrate's)."""
    from galton.client.cli.calibrate import parse_bounds
    from galton.client.sdk.calibration import bounds_for

    try:
        chosen = bounds_for(split_list(fit, "--calibrate"), parse_bounds(bounds))
    except Exception as error:
        raise typer.BadParameter(str(error), param_hint="--calibrate") from error
    return {"fit": chosen, "apply": apply, "max_predictions": max_predictions}


def trigger_value(text: str) -> tuple[float, int]:
    """``--trigger THRESHOLD:WINDOW`` as numbers (the daemon checks their ranges)."""
    threshold, sep, window = text.partition(":")
    try:
        if not sep:
            raise ValueError(text)
        return float(threshold), int(window)
    except ValueError as exc:
        raise typer.BadParameter(f"{text!r}: give THRESHOLD:WINDOW, e.g. 3:4",
                                 param_hint="--trigger") from exc
