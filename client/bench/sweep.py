"""The benchmark over a grid of one or two engine parameters (a fidelity map)."""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from galton.analysis.board import SCENERY_ROLES, BoardSpec, EngineContacts
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.sweep import SweepAxis
from galton.client.bench.executor import Executor, LocalExecutor, TrialHooks
from galton.client.bench.experiment import ExperimentConfig, run_plan
from galton.client.bench.trial import TrialConfig
from galton.client.sdk.client import Client
from galton.protocol import InvalidArgumentError


def parse_axis(text: str) -> SweepAxis:
    """``NAME=V1,V2,...`` (values as JSON; separate by ';' when values hold commas)."""
    name, sep, raw = text.partition("=")
    if not sep or not name or not raw:
        raise InvalidArgumentError(f"--param {text!r} is not NAME=V1,V2,...")
    parts = raw.split(";") if ";" in raw else raw.split(",")
    values = []
    for part in (p.strip() for p in parts if p.strip()):
        try:
            value = json.loads(part)
        except json.JSONDecodeError:
            value = part
        values.append(tuple(value) if isinstance(value, list) else value)
    return SweepAxis(name.strip(), tuple(values))


# A ``default_*`` parameter reaches only bodies that set no surface of their own, and a
# board's bodies carry its materials: so a sweep of one also sets its value on the roles
# it stands for (the balls, or the scenery) wherever the board names a surface for them.
DEFAULT_SURFACES: dict[str, tuple[tuple[str, ...], str]] = {
    "default_friction": (("ball",), "friction"),
    "default_restitution": (("ball",), "restitution"),
    "default_static_friction": (SCENERY_ROLES, "friction"),
    "default_static_restitution": (SCENERY_ROLES, "restitution"),
}


def with_params(board: BoardSpec, engine: str, params: dict[str, Any]) -> BoardSpec:
    """The board with these engine parameters added to its contact settings (a
    ``default_*`` one also on the board's surfaces it stands for: DEFAULT_SURFACES)."""
    contacts = dict(board.contacts)
    current = contacts.get(engine, EngineContacts())
    merged = {**current.params, **{k: list(v) if isinstance(v, tuple) else v
                                   for k, v in params.items()}}
    bodies = dict(current.bodies)
    for name, value in params.items():
        roles, field = DEFAULT_SURFACES.get(name, ((), ""))
        for role in (r for r in roles if r in bodies):
            bodies[role] = replace(bodies[role], **{field: value})
    contacts[engine] = EngineContacts(merged, bodies)
    return board.replace(contacts=contacts)


def sweep_plan(base: ExperimentConfig, axes: Sequence[SweepAxis]) -> list[TrialConfig]:
    """Every trial of the grid: per engine, per grid point, the base plan with the point's
    parameters on that engine's board."""
    if not 1 <= len(axes) <= 2:
        raise InvalidArgumentError(f"a sweep takes one or two --param axes, got {len(axes)}")
    plan: list[TrialConfig] = []
    for engine in base.engines:
        for point in itertools.product(*(a.values for a in axes)):
            params = {a.name: v for a, v in zip(axes, point, strict=True)}
            plan += replace(base, engines=(engine,),
                            board=with_params(base.board, engine, params)).trials()
    return plan


def run_sweep(runner: dict[str, Client] | Executor, base: ExperimentConfig,
              axes: Sequence[SweepAxis],
              on_trial: Callable[[TrialConfig, TrialRecord], None] | None = None,
              ) -> ExperimentResults:
    """Run the base experiment at every grid point, per engine, as one plan through the
    executor (or, given clients, one daemon per engine here); one results set."""
    plan = sweep_plan(base, axes)
    executor = LocalExecutor(runner) if isinstance(runner, dict) else runner
    hooks = TrialHooks(on_trial=None if on_trial is None else (
        lambda _worker, trial, record: on_trial(trial, record)))
    results = run_plan(executor, base, hooks, plan=plan)
    sweep = {"axes": [{"name": a.name, "values": [list(v) if isinstance(v, tuple) else v
                                                   for v in a.values]} for a in axes]}
    return replace(results, extra={**results.extra, "sweep": sweep})
