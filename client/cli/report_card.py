"""``galton-client report-card``: one report across every engine installed.

Scoring and plotting (scipy, matplotlib: the ``[bench]`` extra) are imported inside the
command.
"""

from __future__ import annotations

import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from galton.client.cli.cluster import RayActorsOpt, RayCpusOpt, RayOpt, ray_run, refuse_with_ray
from galton.client.cli.common import console, run_guarded

if TYPE_CHECKING:
    from galton.analysis.card_rules import Rules
    from galton.analysis.laws import LawResults
    from galton.analysis.report_card import CardResults

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

DEFAULT_OUT = Path("galton-report-card")


def offered_engines() -> list[str]:
    """The engines an installed daemon offers (asked of one started for a moment)."""
    from galton.client.sdk.client import Client
    from galton.client.sdk.embedded import EmbeddedDaemon
    with EmbeddedDaemon("mujoco") as daemon, Client(daemon.instance, daemon.endpoint,
                                                     timeout=30.0) as sim:
        return list(sim.capabilities().engines_available)


@commands.command("report-card")
def report_card(
    ctx: typer.Context,
    engines: Annotated[str | None, typer.Option(
        help="Comma-separated engines (default: every engine installed).")] = None,
    quick: Annotated[bool, typer.Option(
        help="Fewer repetitions, a shorter RTF curve (1-300 balls) and shorter timings. "
             "Measured on a quiet 2-core machine (docs/PERFORMANCE.md): MuJoCo 22 s, "
             "PyBullet 19 s, ODE 56 s, DART 245 s; 5 min 45 s for the four.")] = False,
    seed: Annotated[int, typer.Option(min=0)] = 0,
    note: Annotated[str, typer.Option(
        help="A line about the machine for the report (e.g. 'shared, loaded by other "
             "jobs').")] = "",
    out: Annotated[Path, typer.Option(help="Output folder.")] = DEFAULT_OUT,
    pool: Annotated[bool, typer.Option(
        help="Run the Galton trials over the daemons found at --connect (or --instances), "
             "as bench --pool does; when none answers, say so and run them here.")] = False,
    connect: Annotated[str | None, typer.Option(
        help="Endpoint(s) of the pool's daemons (else the global --connect).")] = None,
    instances: Annotated[str | None, typer.Option(
        help="Comma-separated daemon instances of the pool.")] = None,
    weights: Annotated[Path | None, typer.Option(
        help="A TOML of criteria and uses read over the shipped one (card_uses.toml: "
             "thresholds, weights per use; docs/report-card/reading.md).")] = None,
    ray: RayOpt = None,
    ray_cpus_per_daemon: RayCpusOpt = 1.0,
    ray_actors: RayActorsOpt = None,
) -> None:
    """Measure every engine on daemons started here (the Galton board, the physical laws,
    footprint, embedding costs) and write a ranked report card: report-card.md, a
    self-contained report-card.html, card.json and the laws' report under laws/."""
    from galton.analysis.card_rules import load_rules
    from galton.analysis.errors import WeightsError
    from galton.client.report_card import CardPlan, run_card, write_report_card
    from galton.client.report_card.trial_runners import executor_trials, pool_trials
    refuse_with_ray(ray, **{"--pool": pool})
    try:
        rules = load_rules(weights)  # a bad file fails before anything is measured
    except WeightsError as error:
        raise typer.BadParameter(str(error), param_hint="--weights") from error
    plan = CardPlan.quick() if quick else CardPlan()
    chosen = [e.strip() for e in engines.split(",") if e.strip()] if engines else None

    endpoints = connect.split(",") if connect else ctx.obj.connect
    names = [n.strip() for n in instances.split(",") if n.strip()] if instances else None
    pooled: list[str] = []
    executor: dict[str, Any] = {"kind": "local"}

    def say(line: str) -> None:
        console.print(f"[dim]{line}[/dim]", highlight=False)

    def run() -> tuple[CardResults, LawResults]:
        if ray is not None:
            with ray_run(ray, ray_cpus_per_daemon, ray_actors, "mujoco",
                         max(ctx.obj.timeout, 30.0), plan.repetitions) as on_ray:
                say(f"--ray: the Galton trials run on {len(on_ray.workers())} Ray actors")
                try:
                    return run_card(chosen or offered_engines(), plan, seed, say=say,
                                    trials_of=executor_trials(on_ray))
                finally:
                    executor.update(on_ray.describe())
        if not pool:
            return run_card(chosen or offered_engines(), plan, seed, say=say)
        with pool_trials(endpoints, names, max(ctx.obj.timeout, 30.0), say) as (
                trials_of, members):
            pooled.extend(members)
            return run_card(chosen or offered_engines(), plan, seed, say=say,
                            trials_of=trials_of)
    card, laws = run_guarded(run)
    card.config["pool"] = pooled
    card.config["executor"] = executor if not pooled else {"kind": "pool",
                                                           "daemons": len(pooled)}
    card.config |= {"quick": quick, "board_plan": plan.describe(), "machine_note": note,
                    "taken": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                    "command": "galton-client " + shlex.join(sys.argv[1:])}
    written = write_report_card(card, laws, out, rules)
    for line in answer_lines(card, rules):
        typer.echo(line)  # whole lines, never wrapped or cut, in a terminal or a pipe
    typer.echo(f"wrote {', '.join(str(p) for p in written.values())}")


def answer_lines(card: CardResults, rules: Rules) -> list[str]:
    """The card's answer per use, one line each, for the terminal."""
    from galton.analysis.card_rules import percent
    from galton.analysis.report_card import decisions
    return [f"{rules.uses[d.use].title}: "
            + (f"{d.engine} (ahead of {d.rival} by {percent(d.margin)} of the weight)"
               if d.engine else "no clear winner") for d in decisions(card, rules).values()]
