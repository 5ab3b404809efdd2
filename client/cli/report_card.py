"""``galton-client report-card``: one report across every engine installed.

Scoring and plotting (scipy, matplotlib: the ``[bench]`` extra) are imported inside the
command.
"""

from __future__ import annotations

import shlex
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import console, run_guarded

if TYPE_CHECKING:
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
             "Measured on a quiet 2-core machine (docs/PERFORMANCE.md): MuJoCo 29 s, "
             "PyBullet 24 s, ODE 74 s, DART 358 s; 8 min 9 s for the four.")] = False,
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
) -> None:
    """Measure every engine on daemons started here (the Galton board, the physical laws,
    footprint, embedding costs) and write a ranked report card: report-card.md, a
    self-contained report-card.html, card.json and the laws' report under laws/."""
    from galton.client.report_card import CardPlan, run_card, write_report_card
    from galton.client.report_card.pooled import pooled_trials
    plan = CardPlan.quick() if quick else CardPlan()
    chosen = [e.strip() for e in engines.split(",") if e.strip()] if engines else None

    endpoints = connect.split(",") if connect else ctx.obj.connect
    names = [n.strip() for n in instances.split(",") if n.strip()] if instances else None
    pooled: list[str] = []

    def say(line: str) -> None:
        console.print(f"[dim]{line}[/dim]", highlight=False)

    def run() -> tuple[CardResults, LawResults]:
        if not pool:
            return run_card(chosen or offered_engines(), plan, seed, say=say)
        with pooled_trials(endpoints, names, max(ctx.obj.timeout, 30.0), say) as (
                trials_of, members):
            pooled.extend(members)
            return run_card(chosen or offered_engines(), plan, seed, say=say,
                            trials_of=trials_of)
    card, laws = run_guarded(run)
    card.config["pool"] = pooled
    card.config |= {"quick": quick, "board_plan": plan.describe(), "machine_note": note,
                    "taken": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
                    "command": "galton-client " + shlex.join(sys.argv[1:])}
    written = write_report_card(card, laws, out)
    console.print(f"wrote {', '.join(str(p) for p in written.values())}", markup=False)
