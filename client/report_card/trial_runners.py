"""``report-card --pool`` (or ``--ray``): the card's Galton trials (the paper board, its mesh
twin and the RTF curve) spread over the daemons of a pool when they answer (else, said so,
on each engine's own daemon as without --pool), or over Ray actors. Footprint, round trips
and the law suite stay on that engine's own daemon here: they measure one engine alone."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import ExitStack, contextmanager

from galton.analysis.records import TrialRecord
from galton.client.bench.daemons import names_running, pool_clients
from galton.client.bench.executor import Executor
from galton.client.bench.experiment import ExperimentConfig, run_experiment, run_plan
from galton.client.bench.pool_executor import run_pool
from galton.client.sdk.client import Client
from galton.protocol import GaltonError

# A Galton plan run for one engine: (that engine's own client, engine, plan) -> records.
TrialRunner = Callable[[Client, str, ExperimentConfig], list[TrialRecord]]


def local_trials(sim: Client, engine: str, config: ExperimentConfig) -> list[TrialRecord]:
    """The plan on the engine's own daemon (the card without --pool)."""
    return run_experiment({engine: sim}, config).trials


@contextmanager
def pool_trials(connect: list[str] | None, instances: Sequence[str] | None,
                  timeout: float, say: Callable[[str], None]
                  ) -> Iterator[tuple[TrialRunner, list[str]]]:
    """A runner over the pool's daemons and their names, or ``local_trials`` and no names
    (said through ``say``) when no pool was named or none of its daemons answers."""
    if not names_running(connect, instances, False):
        say("--pool: no --connect or --instances names a pool: the Galton trials run on "
            "each engine's own daemon here")
        yield local_trials, []
        return
    with ExitStack() as stack:
        try:
            daemons = stack.enter_context(pool_clients(connect, instances, timeout, 1,
                                                       "mujoco"))
        except GaltonError as error:
            say(f"--pool: no pool daemon answers ({error}); the Galton trials run on each "
                "engine's own daemon here")
            daemons = None
        if daemons is None:
            yield local_trials, []
            return
        names = sorted(daemons.clients)
        say(f"--pool: the Galton trials run on {len(names)} daemons: {', '.join(names)}")

        def on_pool(sim: Client, engine: str, config: ExperimentConfig) -> list[TrialRecord]:
            return run_pool(daemons.clients, config, daemons.hosts).trials
        yield on_pool, names


def executor_trials(executor: Executor) -> TrialRunner:
    """A runner that spreads each plan over ``executor``'s workers (``report-card --ray``:
    Ray actors), whatever engine's daemon the card has open."""
    def on_executor(sim: Client, engine: str, config: ExperimentConfig) -> list[TrialRecord]:
        return run_plan(executor, config).trials
    return on_executor
