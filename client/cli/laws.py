"""``galton-client laws``: the physical-law suite on every engine a daemon offers.

The report's plots need matplotlib (the ``[bench]`` extra), imported inside the command.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer
from rich.table import Table

from galton.client.cli.common import JsonOpt, Target, console, emit, run_guarded
from galton.protocol import GaltonError

if TYPE_CHECKING:
    from galton.analysis.laws import LawResults
    from galton.client.sdk.client import Client

# This group's commands; galton.client.cli.app registers them on the CLI.
commands = typer.Typer()

DEFAULT_OUT = Path("galton-laws")


def _csv(text: str | None) -> list[str] | None:
    items = [part.strip() for part in (text or "").split(",") if part.strip()]
    return items or None


@contextmanager
def _daemon(target: Target, engines: list[str] | None) -> Iterator[Client]:
    """The daemon at --connect, or one started here (on the first engine asked for)."""
    from galton.client.sdk.client import Client
    from galton.client.sdk.embedded import EmbeddedDaemon
    if target.connect:
        with target.client() as client:
            yield client
        return
    with EmbeddedDaemon(engines[0] if engines else "mujoco", zmq=True) as daemon, \
            Client(daemon.instance, daemon.zmq_endpoint, timeout=max(target.timeout, 30.0)
                   ) as client:
        yield client


@commands.command()
def laws(
    ctx: typer.Context,
    engines: Annotated[str | None, typer.Option(
        help="Comma-separated engines (default: every engine the daemon offers).")] = None,
    only: Annotated[str | None, typer.Option(
        help="Comma-separated laws to run, e.g. free-fall,pendulum-small (default all; an "
             "unknown name is refused with the suite's list; docs/PHYSICS.md has them).")
    ] = None,
    seed: Annotated[int, typer.Option(min=0, help="Seeds the torque-free body's wobble.")
                    ] = 0,
    out: Annotated[Path, typer.Option(help="Output folder.")] = DEFAULT_OUT,
    params: Annotated[str | None, typer.Option(
        help="Engine parameters as JSON for every world the suite loads, e.g. "
             "'{\"solver_iterations\": 50}' (default: each engine's defaults).")] = None,
    plots: Annotated[bool, typer.Option(help="Draw the plots (needs matplotlib).")] = True,
    as_json: JsonOpt = False,
) -> None:
    """Measure each engine against closed-form physics (free fall, pendulum, rolling,
    friction, bounce, collisions, a tower, a torque-free spin) and write results.json,
    report.md and plots. With no --connect a daemon is started here."""
    from galton.analysis.laws_report import write_law_outputs
    from galton.client.laws import run_laws
    from galton.client.laws.runner import choose

    wanted = _csv(engines)
    given = _params(params)
    try:  # a usage error, as a bad --engines or --params is: exit 2, before any daemon
        choose(_csv(only))
    except GaltonError as exc:
        raise typer.BadParameter(str(exc), param_hint="--only") from None

    def run() -> LawResults:
        with _daemon(ctx.obj, wanted) as sim:
            return run_laws(sim, wanted, _csv(only), seed, None if as_json else _say, given)
    results = run_guarded(run)
    written = write_law_outputs(results, out, plots)
    emit(results.to_dict(), as_json, lambda: _show(results, written))


def _params(text: str | None) -> dict[str, Any] | None:
    if text is None:
        return None
    try:
        given = json.loads(text)
    except json.JSONDecodeError as error:
        raise typer.BadParameter(f"--params is not JSON ({error}): {text!r}") from error
    if not isinstance(given, dict):
        raise typer.BadParameter(f"--params must be a JSON object, got {text!r}")
    return given


def _say(engine: str, key: str) -> None:
    console.print(f"[dim]{engine}: {key}[/dim]")


def _show(results: LawResults, written: dict[str, Path]) -> None:
    table = Table(title="physical laws (value, pass/FAIL)")
    table.add_column("law")
    table.add_column("quantity")
    table.add_column("theory")
    for record in results.engines:
        table.add_column(record.engine)
    for law, quantity in results.rows():
        checks = [results.check(r.engine, law, quantity) for r in results.engines]
        theory = next(c for c in checks if c is not None).theory
        table.add_row(law, quantity, f"{theory:.6g}", *[
            "not run" if c is None else "—" if c.value is None else
            f"{c.value:.6g} {'pass' if c.passed else 'FAIL'}" for c in checks])
    console.print(table)
    for record in results.engines:
        console.print(f"{record.engine}: {record.passed} of {len(record.checks)} pass")
    console.print(f"wrote {', '.join(str(p) for p in written.values())}", markup=False)
