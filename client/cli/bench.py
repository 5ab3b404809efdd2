"""``galton-client bench``, ``report`` and ``sweep``: the Galton-board benchmark.

Scoring and plotting (scipy, matplotlib: the ``[bench]`` extra) are imported inside the
commands, so that a client installed without them still has every other command.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from contextlib import ExitStack
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.analysis.errors import AnalysisError
from galton.analysis.published import PUBLISHED_LABEL, PUBLISHED_TABLE2
from galton.client.bench.defaults import (
    DEFAULT_BALLS,
    DEFAULT_ENGINES,
    DEFAULT_MAX_SIM_TIME_S,
    DEFAULT_REPETITIONS,
    default_pool_size,
)
from galton.client.cli.cluster import RayActorsOpt, RayCpusOpt, RayOpt, ray_run, refuse_with_ray
from galton.client.cli.common import JsonOpt, console, fail, run_guarded
from galton.protocol import GaltonError

if TYPE_CHECKING:
    from rich.progress import Progress

    from galton.analysis.board import BoardSpec
    from galton.analysis.records import ExperimentResults, TrialRecord
    from galton.client.bench.executor import Executor, Failover, Retry
    from galton.client.bench.experiment import ExperimentConfig
    from galton.client.bench.journal import Journal
    from galton.client.bench.picture import Animation
    from galton.client.bench.trial import TrialConfig
    from galton.client.sdk.client import Client
    from galton.client.transport.credentials import Credentials

if TYPE_CHECKING:
    from galton.analysis.summary import EngineSummary

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

DEFAULT_OUT = Path("galton-results")


def _csv(text: str, where: str) -> list[str]:
    items = [part.strip() for part in text.split(",") if part.strip()]
    if not items:
        raise typer.BadParameter(f"{where} needs at least one value")
    return items


def _ints(text: str, where: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in _csv(text, where))
    except ValueError:
        raise typer.BadParameter(f"{where} must be comma-separated integers, got {text!r}") \
            from None


def checked(make: Callable[[], ExperimentConfig]) -> ExperimentConfig:
    """The run's configuration, or a command-line error (exit 2) before anything starts."""
    try:
        return make()
    except GaltonError as error:
        raise typer.BadParameter(str(error)) from error


MaterialsOpt = Annotated[str | None, typer.Option(
    help="board: the board's materials (its per-engine contacts: each body's friction and "
         "restitution, the engine settings they were calibrated with); engine: none of "
         "them, each engine's own defaults (default: the board's `materials`, board).")]


def load_board(source: str, materials: str | None = None) -> BoardSpec:
    """The board, with the materials asked for (None: as the board says)."""
    from galton.analysis.board import MATERIALS, BoardSpec
    if materials is not None and materials not in MATERIALS:
        raise typer.BadParameter(f"--materials must be one of {', '.join(MATERIALS)}, got "
                                 f"{materials!r}")
    try:
        spec = BoardSpec.load(source)
    except (AnalysisError, OSError) as error:
        raise typer.BadParameter(f"--board {source!r}: {error}") from error
    return spec if materials is None else spec.replace(materials=materials)


@commands.command()
def bench(
    ctx: typer.Context,
    engines: Annotated[str, typer.Option(help="Comma-separated engines.")] = ",".join(
        DEFAULT_ENGINES),
    connect: Annotated[str | None, typer.Option(
        help="Endpoint(s) of daemons to run on, whose worlds the trials replace (else the "
             "global --connect; with neither, nor --instances or --use-running, the bench "
             "starts daemons of its own).")
    ] = None,
    instances: Annotated[str | None, typer.Option(
        help="Comma-separated daemon instances to use, in engine order.")] = None,
    use_running: Annotated[bool, typer.Option(
        help="Run on the daemons already answering on the default endpoint. A trial "
             "replaces a daemon's world, so without this (or --connect/--instances) the "
             "bench starts daemons of its own and touches no running one.")] = False,
    board: Annotated[str, typer.Option(
        help="Preset (paper, paper-mesh, paper-webots, paper-gazebo, small) or a TOML/JSON file.")
                     ] = "paper",
    materials: MaterialsOpt = None,
    balls: Annotated[str, typer.Option(help="Ball count(s), e.g. 1,25,100.")] = ",".join(
        map(str, DEFAULT_BALLS)),
    repetitions: Annotated[int, typer.Option(min=1)] = DEFAULT_REPETITIONS,
    release: Annotated[str | None, typer.Option(
        help="all-at-once or stream (default: the board's).")] = None,
    seed: Annotated[int, typer.Option(min=0)] = 0,
    max_sim_time: Annotated[float, typer.Option(help="Sim-time cap per trial, s.", min=0.1)
                            ] = DEFAULT_MAX_SIM_TIME_S,
    out: Annotated[Path, typer.Option(help="Output folder.")] = DEFAULT_OUT,
    animation: Annotated[bool, typer.Option(
        help="Also replay each engine's first trial as an animated PNG for the report.")
    ] = False,
    record: Annotated[bool, typer.Option(
        help="Also record each trial (OUT/recordings/*.npz) for `galton-client view OUT`.")
    ] = False,
    pool: Annotated[bool, typer.Option(
        help="Spread the trials over every daemon found at --connect (or --instances), a "
             "dead daemon's trial re-run on the others; with no --connect and none running, "
             "start --pool-size daemons here.")] = False,
    pool_size: Annotated[int, typer.Option(
        help="Embedded daemons for --pool when none runs (default: cores, at most 4).",
        min=1)] = default_pool_size(),
    ray: RayOpt = None,
    ray_cpus_per_daemon: RayCpusOpt = 1.0,
    ray_actors: RayActorsOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """Run the paper's Galton-board experiment through the bridge and report it, with a
    picture of the board after each engine's first trial."""
    from galton.client.bench.experiment import ExperimentConfig
    from galton.client.bench.journal import Journal
    from galton.client.bench.picture import Animation
    if release is not None and release not in ("all-at-once", "stream"):
        raise typer.BadParameter(f"--release must be all-at-once or stream, got {release!r}")
    refuse_with_ray(ray, **{"--pool": pool, "--connect": connect, "--instances": instances,
                            "--use-running": use_running})
    config = checked(lambda: ExperimentConfig(
        board=load_board(board, materials), engines=tuple(_csv(engines, "--engines")),
        balls=_ints(balls, "--balls"), repetitions=repetitions, release=release, seed=seed,
        max_sim_time=max_sim_time, recordings=out / "recordings" if record else None))
    endpoints = connect.split(",") if connect else ctx.obj.connect
    names = _csv(instances, "--instances") if instances else None
    shown = Animation() if animation else None
    journal = Journal(config, out)
    if ray is not None:
        results = _kept(journal, lambda: _run_ray(
            config, ray, ray_cpus_per_daemon, ray_actors, ctx.obj.timeout, as_json, out,
            shown, journal))
    elif pool:
        results = _kept(journal, lambda: _run_pool(
            config, endpoints, names, ctx.obj.timeout, pool_size, as_json, out, shown,
            ctx.obj.credentials, use_running, journal))
    else:
        results = _kept(journal, lambda: _run(
            config, endpoints, names, ctx.obj.timeout, as_json, out, shown,
            ctx.obj.credentials, use_running, journal))
    _finish(results, out, as_json)


def _kept(journal: Journal, action: Callable[[], ExperimentResults]) -> ExperimentResults:
    """Run the trials; on a failure, say which trials were kept (journal) and exit 1."""
    try:
        return action()
    except GaltonError as error:
        if journal.count:
            typer.echo(f"galton-client: {journal.count} trial(s) finished before the failure "
                       f"are kept in {journal.path} (`galton-client report {journal.path}` "
                       "reports them)", err=True)
        raise fail(error) from error


def _run(config: ExperimentConfig, connect: list[str] | None, instances: list[str] | None,
         timeout: float, quiet: bool, pictures: Path | None = None,
         animation: Animation | None = None, credentials: Credentials | None = None,
         use_running: bool = False, journal: Journal | None = None) -> ExperimentResults:
    from galton.client.bench.daemons import bench_clients
    from galton.client.bench.experiment import run_experiment
    plan = config.trials()
    if journal is not None:
        journal.executor = {"kind": "local"}
    with bench_clients(config.engines, connect, instances, max(timeout, 30.0),
                       credentials, use_running) as clients, \
            _progress(quiet) as progress:
        task = progress.add_task("Galton trials", total=len(plan))

        def advance(trial: TrialConfig, record: TrialRecord) -> None:
            if journal is not None:
                journal.add(trial, record)
            progress.update(task, advance=1, description=(
                f"{trial.engine} {trial.balls} balls rep {trial.repetition + 1}: "
                f"lost {record.lost}, RTF {record.rtf or 0:.2f}"))
        return run_experiment(clients, config, advance, pictures, animation)


def _run_pool(config: ExperimentConfig, connect: list[str] | None,
              instances: list[str] | None, timeout: float, size: int, quiet: bool,
              pictures: Path, animation: Animation | None,
              credentials: Credentials | None = None, use_running: bool = False,
              journal: Journal | None = None) -> ExperimentResults:
    """The plan over a pool of daemons: a progress row per daemon and one for the whole."""
    from galton.client.bench.daemons import pool_clients
    from galton.client.bench.pool_executor import PoolExecutor
    with pool_clients(connect, instances, max(timeout, 30.0), size, config.engines[0],
                      credentials, use_running) as daemons:
        return _run_spread(PoolExecutor(daemons.clients, daemons.hosts), config, quiet,
                           pictures, animation, journal)


def _run_ray(config: ExperimentConfig, address: str, cpus_per_daemon: float,
             actors: int | None, timeout: float, quiet: bool, pictures: Path,
             animation: Animation | None, journal: Journal | None = None) -> ExperimentResults:
    """The plan over Ray actors, each with a daemon of its own: rows as for the pool."""
    with ray_run(address, cpus_per_daemon, actors, config.engines[0], max(timeout, 30.0),
                 len(config.trials())) as executor:
        return _run_spread(executor, config, quiet, pictures, animation, journal)


def _run_spread(executor: Executor, config: ExperimentConfig, quiet: bool, pictures: Path,
                animation: Animation | None, journal: Journal | None = None
                ) -> ExperimentResults:
    """The plan through an executor of several workers (a pool's daemons, Ray's actors):
    a progress row per worker and one for the whole; the journal rewritten after each
    trial, and each dropped daemon or retried trial said."""
    from galton.client.bench.executor import TrialHooks
    from galton.client.bench.experiment import run_plan
    workers = executor.workers()
    if journal is not None:
        journal.executor = executor.describe()
    with _progress(quiet) as progress:
        overall = progress.add_task(f"Galton trials on {len(workers)} "
                                    f"{_workers_word(executor)}", total=len(config.trials()))
        rows = {name: progress.add_task(f"{name}: starting", total=None) for name in workers}

        def start(name: str, trial: TrialConfig) -> None:
            progress.update(rows[name], description=f"{name}: {_trial_text(trial)}")

        def advance(name: str, trial: TrialConfig, record: TrialRecord) -> None:
            if journal is not None:
                journal.executor = executor.describe()  # with the retries so far
                journal.add(trial, record)
            progress.update(rows[name], advance=1, description=(
                f"{name}: {_trial_text(trial)}: lost {record.lost}, RTF {record.rtf or 0:.2f}"))
            progress.update(overall, advance=1)

        def dropped(failover: Failover) -> None:
            progress.update(rows[failover.daemon], description=(
                f"{failover.daemon}: dropped, trial {failover.trial + 1} re-queued "
                f"({failover.error})"))

        def retried(retry: Retry) -> None:
            if not quiet:
                progress.console.print(
                    f"{retry.worker}: trial {retry.trial + 1} ({retry.engine} {retry.balls} "
                    f"balls rep {retry.repetition + 1}) retried: {retry.reason}", markup=False)
        hooks = TrialHooks(on_start=start, on_trial=advance, on_drop=dropped, on_retry=retried)
        return run_plan(executor, config, hooks, pictures, animation)


def _workers_word(executor: Executor) -> str:
    return "Ray actors" if executor.describe()["kind"] == "ray" else "daemons"


def _trial_text(trial: TrialConfig) -> str:
    return f"{trial.engine} {trial.balls} balls rep {trial.repetition + 1}"


def _finish(results: ExperimentResults, out: Path, as_json: bool) -> None:
    from galton.analysis.outputs import write_outputs
    from galton.analysis.records import ExperimentResults
    from galton.analysis.summary import summarise
    try:
        written = write_outputs(results, out)
        saved = ExperimentResults.from_json(written["results_json"])
        summaries = summarise(saved.trials)
    except AnalysisError as error:
        typer.echo(f"galton-client: {type(error).__name__}: {error}", err=True)
        raise typer.Exit(1) from error
    if as_json:
        typer.echo(json.dumps({"files": {k: str(v) for k, v in written.items()},
                               "engines": [_headline(s) for s in summaries],
                               "executor": saved.executor}, indent=2))
        return
    console.print(table2(summaries, saved.trials[0].rows if saved.trials else 11))
    for line in executor_lines(saved.executor):
        console.print(line, markup=False, highlight=False)
    console.print(f"Report, results and plots in {out}/ (report.md, results.json, results.csv, "
                  "*.png)")


def executor_lines(executor: dict[str, Any]) -> list[str]:
    """Where the trials ran, when not here, and every trial Ray retried."""
    if executor.get("kind") != "ray":
        return []
    retried = executor.get("retried", [])
    lines = [f"Ran on Ray ({executor['address']}): {executor['actors']} actor(s) on "
             f"{executor['nodes']} node(s); {len(retried) or 'no'} trial(s) retried"]
    lines += [f"  retried: trial {r['trial'] + 1} ({r['engine']} {r['balls']} balls rep "
              f"{r['repetition'] + 1}) on {r['worker']}: {r['reason']}" for r in retried]
    return lines


def _headline(summary: EngineSummary) -> dict[str, Any]:
    group = summary.overall
    return {"engine": summary.label, "chi2_median": group.chi2_median,
            "chi2_pooled": group.pooled.chi2 if group.pooled else None,
            "p_monte_carlo_pooled": group.pooled.p_monte_carlo if group.pooled else None,
            "effect_size_pooled": group.pooled.effect_size if group.pooled else None,
            "lost_percent": group.lost_percent_pooled, "rtf_mean": group.rtf_mean,
            "rtf_min": group.rtf_min, "rtf_max": group.rtf_max}


def table2(summaries: list[EngineSummary], rows: int = 11) -> Table:
    """Our engines beside the paper's published rows, as in its Table 2."""
    from galton.analysis.stats import critical_value
    title = (f"Galton board, {rows} d.o.f., critical value {critical_value(dof=rows):.2f} at 5 %"
             " (published rows: the paper's 11-row board)")
    table = Table("simulator", "chi-squared (median per trial)", "chi-squared pooled (MC p)",
                  "lost balls (%)", "real-time factor", title=title)
    for s in summaries:
        h = _headline(s)
        pooled = "–" if h["chi2_pooled"] is None else (
            f"{h['chi2_pooled']:.2f} (p={h['p_monte_carlo_pooled']:.3f})")
        rtf = "–" if h["rtf_mean"] is None else (
            f"{h['rtf_mean']:.2f} [{h['rtf_min']:.2f}–{h['rtf_max']:.2f}]")
        median = "–" if h["chi2_median"] is None else f"{h['chi2_median']:.2f}"
        table.add_row(f"{s.label} {s.engine_version} (this run)", median, pooled,
                      f"{h['lost_percent']:.1f}", rtf)
    for row in PUBLISHED_TABLE2:
        table.add_row(f"{row.simulator} ({PUBLISHED_LABEL})", f"{row.chi2:.2f}", "–",
                      f"{row.lost_percent:.1f}", row.rtf_text, style="dim")
    return table


@commands.command()
def report(
    results_json: Annotated[Path, typer.Argument(help="A results.json written by bench.",
                                                 exists=True, dir_okay=False)],
    out: Annotated[Path | None, typer.Option(help="Output folder (default: beside it).")
                   ] = None,
    as_json: JsonOpt = False,
) -> None:
    """Re-render the report, CSV and plots from saved results."""
    from galton.analysis.records import ExperimentResults
    def load() -> ExperimentResults:
        try:
            return ExperimentResults.from_json(results_json)
        except (AnalysisError, ValueError) as error:
            raise typer.BadParameter(f"{results_json}: {error}") from error
    _finish(load(), out or results_json.parent, as_json)


@commands.command()
def sweep(
    ctx: typer.Context,
    param: Annotated[list[str], typer.Option(
        help="NAME=V1,V2,... engine parameter values (one or two --param); e.g. "
             "default_restitution=0.3,0.5,0.7 or 'mujoco.solref=[0.02,0.3];[0.02,0.5]'. A "
             "default_* value is also set on the board's surfaces it stands for (the balls' "
             "or the scenery's), which carry the board's materials.")],
    engines: Annotated[str, typer.Option(help="Comma-separated engines.")] = ",".join(
        DEFAULT_ENGINES),
    connect: Annotated[str | None, typer.Option(help="Endpoint(s) of remote daemons.")] = None,
    instances: Annotated[str | None, typer.Option(help="Daemon instances to use.")] = None,
    use_running: Annotated[bool, typer.Option(
        help="Run on the daemons already answering on the default endpoint (their worlds "
             "are replaced); else the sweep starts its own.")] = False,
    board: Annotated[str, typer.Option(help="Preset or TOML/JSON file.")] = "paper",
    materials: MaterialsOpt = None,
    balls: Annotated[int, typer.Option(min=1)] = 100,
    repetitions: Annotated[int, typer.Option(min=1)] = 3,
    release: Annotated[str | None, typer.Option(help="all-at-once or stream.")] = None,
    seed: Annotated[int, typer.Option(min=0)] = 0,
    max_sim_time: Annotated[float, typer.Option(min=0.1)] = DEFAULT_MAX_SIM_TIME_S,
    out: Annotated[Path, typer.Option(help="Output folder.")] = Path("galton-sweep"),
    ray: RayOpt = None,
    ray_cpus_per_daemon: RayCpusOpt = 1.0,
    ray_actors: RayActorsOpt = None,
    as_json: JsonOpt = False,
) -> None:
    """The benchmark over a grid of one or two parameters: a fidelity map per engine."""
    from galton.analysis.sweep import plot_sweep, sweep_cells, sweep_table
    from galton.client.bench.daemons import bench_clients
    from galton.client.bench.experiment import ExperimentConfig
    from galton.client.bench.sweep import parse_axis, run_sweep
    refuse_with_ray(ray, **{"--connect": connect, "--instances": instances,
                            "--use-running": use_running})
    axes = run_guarded(lambda: [parse_axis(p) for p in param])
    config = checked(lambda: ExperimentConfig(
        board=load_board(board, materials), engines=tuple(_csv(engines, "--engines")),
        balls=(balls,),
        repetitions=repetitions, release=release, seed=seed, max_sim_time=max_sim_time))
    endpoints = connect.split(",") if connect else ctx.obj.connect
    names = _csv(instances, "--instances") if instances else None
    total = len(config.trials()) * len(list(itertools.product(*(a.values for a in axes))))

    def go() -> ExperimentResults:
        with ExitStack() as stack:
            runner: dict[str, Client] | Executor
            if ray is None:
                runner = stack.enter_context(bench_clients(
                    config.engines, endpoints, names, max(ctx.obj.timeout, 30.0),
                    ctx.obj.credentials, use_running))
            else:
                runner = stack.enter_context(ray_run(
                    ray, ray_cpus_per_daemon, ray_actors, config.engines[0],
                    max(ctx.obj.timeout, 30.0), total))
            progress = stack.enter_context(_progress(as_json))
            task = progress.add_task("sweep", total=total)
            return run_sweep(runner, config, axes,
                             lambda t, r: progress.update(task, advance=1))
    results = run_guarded(go)
    out.mkdir(parents=True, exist_ok=True)
    results.to_json(out / "results.json")
    cells = sweep_cells(results.trials, axes)
    table = sweep_table(cells, axes)
    (out / "sweep.md").write_text(f"# Fidelity sweep\n\n{table}", encoding="utf-8")
    plots = [plot_sweep(cells, axes, engine, out) for engine in config.engines]
    if as_json:
        typer.echo(json.dumps({"cells": [c.to_dict() for c in cells],
                               "files": [str(p) for p in plots]}, indent=2))
    else:
        console.print(table)
        for line in executor_lines(results.executor):
            console.print(line, markup=False, highlight=False)
        console.print(f"Fidelity maps and results in {out}/")


def _progress(quiet: bool) -> Progress:
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
    return Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                    TimeElapsedColumn(), console=console, disable=quiet)
