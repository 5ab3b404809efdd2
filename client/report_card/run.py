"""Assemble the report card: for every engine, the Galton board (fidelity and the
RTF-versus-balls curve), the law suite, the footprint and the embedding costs, each on a
daemon of that engine alone (so its memory is that engine's)."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from galton.analysis.board import BoardSpec
from galton.analysis.laws import LawResults
from galton.analysis.report_card import CardResults
from galton.client.bench.experiment import ExperimentConfig
from galton.client.laws import choose, run_engine
from galton.client.report_card import measure
from galton.client.report_card.pooled import TrialRunner, local_trials
from galton.client.sdk.client import Client
from galton.client.sdk.embedded import EmbeddedDaemon

Say = Callable[[str], None]


@dataclass(frozen=True)
class CardPlan:
    """How much of each measure to take: ``quick`` fits 10 minutes on 2 cores."""

    fidelity_balls: int = 100
    repetitions: int = 10
    curve: tuple[int, ...] = (1, 10, 1000)
    footprint_s: float = 10.0
    round_trips: int = 500
    world_ops: int = 20
    laws: tuple[str, ...] | None = None  # None: the whole suite
    mesh_balls: int = 100  # the paper-mesh board's trials
    mesh_repetitions: int = 10
    # Sim seconds, and physics wall seconds, each RTF-curve trial may run (its RTF needs no
    # settled board): DART's 1,000-ball crowd runs at RTF ~0.0003.
    curve_sim_time: float = 10.0
    curve_wall_time: float = 60.0

    @classmethod
    def quick(cls) -> CardPlan:
        return cls(repetitions=4, curve=(1, 10, 300), footprint_s=3.0, round_trips=100,
                   world_ops=6, mesh_balls=25, mesh_repetitions=2, curve_sim_time=2.0,
                   curve_wall_time=15.0)

    def describe(self) -> str:
        return (f"paper, {self.fidelity_balls} balls × {self.repetitions}, all at once; "
                f"paper-mesh, {self.mesh_balls} balls × {self.mesh_repetitions}; "
                f"RTF curve at {', '.join(map(str, sorted({*self.curve, self.fidelity_balls})))} "
                f"balls (curve trials at most {self.curve_sim_time:g} s of sim time and "
                f"{self.curve_wall_time:g} s of wall time)")


@contextmanager
def engine_daemon(engine: str, timeout: float) -> Iterator[tuple[Client, Client]]:
    """A daemon of ``engine`` here, and a client on each of its transports."""
    with EmbeddedDaemon(engine, zmq=True) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=timeout) as zenoh_client, \
            Client(daemon.instance, daemon.zmq_endpoint, timeout=timeout) as zmq_client:
        yield zenoh_client, zmq_client


def board_measures(sim: Client, engine: str, plan: CardPlan, seed: int,
                   trials_of: TrialRunner = local_trials
                   ) -> tuple[dict[str, float | None], dict[int, float], int]:
    """Fidelity at the plan's ball count, the RTF curve (mean RTF per ball count), and
    the balls lost to a diverged (NaN) state."""
    from galton.analysis.summary import summarise_group  # scipy: the [bench] extra

    board = BoardSpec.load("paper")
    fidelity = ExperimentConfig(board=board, engines=(engine,), balls=(plan.fidelity_balls,),
                                repetitions=plan.repetitions, seed=seed)
    curve = ExperimentConfig(board=board, engines=(engine,), balls=plan.curve, repetitions=1,
                             seed=seed, max_sim_time=plan.curve_sim_time,
                             max_wall_time=plan.curve_wall_time)
    trials = [*trials_of(sim, engine, fidelity), *trials_of(sim, engine, curve)]
    group = summarise_group([t for t in trials if t.balls == plan.fidelity_balls],
                            plan.fidelity_balls)
    rtfs: dict[int, list[float]] = {}
    for trial in trials:
        if trial.rtf is not None:
            rtfs.setdefault(trial.balls, []).append(trial.rtf)
    means = {n: statistics.fmean(v) for n, v in sorted(rtfs.items())}
    return ({"board_chi2_median": group.chi2_median,
             "board_pooled_p": None if group.pooled is None else group.pooled.p_monte_carlo,
             "board_lost_percent": group.lost_percent_pooled,
             "rtf_100": means.get(plan.fidelity_balls)},
            means, sum(t.lost_by_reason.get("nan", 0) for t in trials))


def mesh_measures(sim: Client, engine: str, plan: CardPlan, seed: int,
                  trials_of: TrialRunner = local_trials) -> dict[str, float | None]:
    """The paper-mesh board's median χ² and balls lost, beside the primitives'."""
    from galton.analysis.summary import summarise_group  # scipy: the [bench] extra

    config = ExperimentConfig(board=BoardSpec.load("paper-mesh"), engines=(engine,),
                              balls=(plan.mesh_balls,), repetitions=plan.mesh_repetitions,
                              seed=seed)
    group = summarise_group(trials_of(sim, engine, config), plan.mesh_balls)
    return {"mesh_chi2_median": group.chi2_median,
            "mesh_lost_percent": group.lost_percent_pooled}


def run_card(engines: Sequence[str], plan: CardPlan, seed: int = 0, timeout: float = 30.0,
             say: Say | None = None, trials_of: TrialRunner = local_trials
             ) -> tuple[CardResults, LawResults]:
    """Every measure of every engine, each engine on a daemon of its own; the Galton
    trials through ``trials_of`` (``report-card --pool``: over a pool)."""
    card = CardResults(measures={}, config={"plan": plan.describe(), "seed": seed})
    law_records = []
    tell = say or (lambda _: None)
    board = BoardSpec.load("paper")
    for engine in engines:
        began = time.perf_counter()
        with engine_daemon(engine, timeout) as (zenoh_client, zmq_client):
            caps = zenoh_client.capabilities()
            card.versions[engine] = caps.engine_version
            card.config.setdefault("host", caps.host)
            measures: dict[str, float | None] = {}
            tell(f"{engine}: footprint")
            measures |= measure.footprint(zmq_client, engine, board, plan.footprint_s)
            tell(f"{engine}: round trips and world operations")
            measure.busy_world(zmq_client, engine, board)
            for name, client in (("zenoh", zenoh_client), ("zmq", zmq_client)):
                status_ms, step_ms = measure.round_trips(client, plan.round_trips)
                measures[f"status_{name}_ms"] = status_ms
                measures[f"step_{name}_ms"] = step_ms
            costs, restore_errors = measure.world_costs(zmq_client, plan.world_ops)
            measures |= costs
            tell(f"{engine}: the physical laws")
            laws = run_engine(zmq_client, engine, choose(plan.laws), seed)
            law_records.append(laws)
            measures["laws_passed"] = float(laws.passed)
            tell(f"{engine}: the Galton board")
            board_values, curve, diverged = board_measures(zmq_client, engine, plan, seed,
                                                           trials_of)
            measures |= board_values
            card.curves[engine] = curve
            if "mesh" in caps.body_shapes:
                tell(f"{engine}: the Galton board as meshes")
                measures |= mesh_measures(zmq_client, engine, plan, seed, trials_of)
            failed = [c for c in laws.checks if c.value is None]
            measures["physics_errors"] = float(len(failed) + diverged + restore_errors)
            notes = card.config.setdefault("notes", [])
            notes += [f"{engine}: law {c.law} did not run: {c.note}" for c in failed]
            if diverged:
                notes.append(f"{engine}: {diverged} Galton ball(s) lost to a diverged state")
            if restore_errors:
                notes.append(f"{engine}: stepping after restore (board and 100 balls) "
                             "diverged: PHYSICS_ERROR")
        card.measures[engine] = measures
        tell(f"{engine}: done in {time.perf_counter() - began:.0f} s")
    return card, LawResults(law_records, {"engines": list(engines),
                                          "laws": [e.key for e in choose(plan.laws)],
                                          "seed": seed})


def write_report_card(card: CardResults, laws: LawResults, out: Path) -> dict[str, Path]:
    """The card's files in ``out`` and the laws' report in ``out/laws``, its plots inlined
    in the card's HTML page too."""
    from galton.analysis.laws_report import write_law_outputs
    from galton.analysis.report_card_outputs import write_card_outputs

    written = write_law_outputs(laws, out / "laws")
    images = [path for path in written.values() if path.suffix == ".png"]
    return {**write_card_outputs(card, out, extra_images=images),
            **{f"laws/{key}": path for key, path in written.items()}}
