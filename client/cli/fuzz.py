"""``galton-client fuzz``: a seeded fuzz campaign against a daemon (``galton.client.fuzz``)."""

from __future__ import annotations

import json
from contextlib import ExitStack
from typing import TYPE_CHECKING, Annotated

import typer

from galton.client.cli.common import JsonOpt, console, run_guarded

if TYPE_CHECKING:

    from galton.client.fuzz.campaign import FuzzReport

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()


@commands.command()
def fuzz(
    ctx: typer.Context,
    requests: Annotated[int, typer.Option(help="Requests to send.", min=1)] = 2000,
    seed: Annotated[int, typer.Option(help="Seed of the request generator.")] = 0,
    resealed: Annotated[int, typer.Option(
        help="Re-sealed corrupt snapshots to restore after the requests.", min=0)] = 100,
    oversize: Annotated[bool, typer.Option(
        help="Then send requests whose replies would pass the daemon's max_reply_bytes "
             "(each must be refused and change nothing).")] = True,
    unread: Annotated[int, typer.Option(
        help="Then pipeline this many requests from a ZeroMQ client that never reads them, "
             "while others ask for status (0: none; needs the daemon's ZeroMQ front).",
        min=0)] = 1800,
    engine: Annotated[str | None, typer.Option(
        help="Fuzz a fresh embedded daemon of this engine instead of --connect/--instance.")
    ] = None,
    zmq: Annotated[bool, typer.Option(
        "--zmq", help="With --engine: the daemon serves ZeroMQ too, and the campaign's "
        "requests go over it.")] = False,
    as_json: JsonOpt = False,
) -> None:
    """Send seeded malformed and well-formed requests; check each gets one typed reply and
    that a rejected one changes nothing. Exit 1 on any finding."""
    from rich.progress import Progress

    from galton.client.fuzz.campaign import run_campaign
    from galton.client.sdk.client import Client
    from galton.client.sdk.embedded import EmbeddedDaemon
    def go() -> FuzzReport:
        with ExitStack() as stack:
            daemon = None
            if engine is not None:
                daemon = stack.enter_context(EmbeddedDaemon(engine, instance=f"fuzz-{engine}",
                                                            zmq=zmq))
                client = stack.enter_context(Client(
                    daemon.instance, daemon.zmq_endpoint or daemon.endpoint, timeout=30.0))
            else:
                client = stack.enter_context(ctx.obj.client())
            progress = stack.enter_context(Progress(console=console, disable=as_json))
            task = progress.add_task(f"fuzz (seed {seed})", total=requests)
            report = run_campaign(client, requests, seed,
                                  lambda done: progress.update(task, completed=done),
                                  resealed=resealed, oversize_cases=oversize,
                                  unread=unread)
            if daemon is not None and daemon.process is not None and \
                    daemon.process.poll() is not None:
                report.missing_replies.append(f"the daemon exited ({daemon.process.poll()})")
            return report
    report = run_guarded(go)
    if as_json:
        typer.echo(json.dumps(report.to_dict(), indent=2))
    else:
        _render(report)
    raise typer.Exit(0 if report.ok else 1)


def _render(report: FuzzReport) -> None:
    codes = ", ".join(f"{name} {count}" for name, count in report.codes.most_common())
    console.print(f"{report.requests} requests in {report.seconds:.1f} s (seed {report.seed}): "
                  f"{codes}")
    for title, found in (("missing replies", report.missing_replies),
                         ("untyped replies", report.untyped_replies),
                         ("side effects of rejected requests", report.side_effects),
                         ("bad restores of re-sealed snapshots", report.bad_restores),
                         (f"over-limit requests answered (of {report.oversize_cases})",
                          report.oversize_answered),
                         (f"status starved by {report.unread_sent} unread requests",
                          report.starved)):
        console.print(f"{title}: {len(found)}")
        for line in found[:10]:
            console.print(f"  {line}", markup=False)
    for line in report.skipped:
        console.print(f"skipped: {line}", markup=False)
