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

from galton.analysis import card_intervals
from galton.analysis.board import BoardSpec
from galton.analysis.card_intervals import BoardTrial, Measure
from galton.analysis.card_rules import Rules
from galton.analysis.laws import EngineLaws, LawResults
from galton.analysis.records import TrialRecord
from galton.analysis.report_card import CardResults
from galton.client.bench.experiment import ExperimentConfig
from galton.client.laws import choose, run_engine
from galton.client.report_card import calibrated, measure
from galton.client.report_card.trial_runners import TrialRunner, local_trials
from galton.client.sdk.client import Client
from galton.client.sdk.embedded import EmbeddedDaemon
from galton.protocol import RemoteError

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
    # Fidelity after calibration (client/report_card/calibrated.py): fits, each of at most
    # this many predictions; the interval is over the fits' seeds.
    calibration_seeds: int = 5
    calibration_predictions: int = 150

    @classmethod
    def quick(cls) -> CardPlan:
        return cls(repetitions=4, curve=(1, 10, 300), footprint_s=3.0, round_trips=100,
                   world_ops=6, mesh_balls=25, mesh_repetitions=2, curve_sim_time=2.0,
                   curve_wall_time=15.0, calibration_seeds=2, calibration_predictions=40)

    def describe(self) -> str:
        return (f"paper, {self.fidelity_balls} balls × {self.repetitions}, all at once; "
                f"paper-mesh, {self.mesh_balls} balls × {self.mesh_repetitions}; "
                f"RTF curve at {', '.join(map(str, sorted({*self.curve, self.fidelity_balls})))} "
                f"balls (curve trials at most {self.curve_sim_time:g} s of sim time and "
                f"{self.curve_wall_time:g} s of wall time); fidelity after calibration: "
                f"{self.calibration_seeds} fits of {self.calibration_predictions} "
                "predictions")


@contextmanager
def engine_daemon(engine: str, timeout: float) -> Iterator[tuple[Client, Client]]:
    """A daemon of ``engine`` here, and a client on each of its transports."""
    with EmbeddedDaemon(engine, zmq=True) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=timeout) as zenoh_client, \
            Client(daemon.instance, daemon.zmq_endpoint, timeout=timeout) as zmq_client:
        yield zenoh_client, zmq_client


def calibrated_measures(sim: Client, engine: str, plan: CardPlan, card: CardResults
                        ) -> dict[str, Measure | None]:
    """The sliding box's and bouncing ball's error against their analytic reference, with
    the reference's values and once fitted; a failed fit is a note, the card goes on."""
    try:
        return calibrated.calibrated_fidelity(sim, engine, plan.calibration_seeds,
                                              plan.calibration_predictions)
    except RemoteError as error:
        card.config.setdefault("notes", []).append(
            f"{engine}: fidelity after calibration did not run: {error}")
        return dict.fromkeys(calibrated.MEASURES)


def board_trial(trial: TrialRecord) -> BoardTrial:
    return BoardTrial(tuple(trial.counts), trial.lost, trial.balls)


@dataclass
class BoardRun:
    """One engine's Galton figures: measures, trials kept, the RTF curve, diverged balls."""

    measures: dict[str, Measure | None]
    trials: list[BoardTrial]
    curve: dict[int, float]
    diverged: int
    released: int


def board_measures(sim: Client, engine: str, plan: CardPlan, seed: int,
                   trials_of: TrialRunner = local_trials) -> BoardRun:
    """Fidelity at the plan's ball count (bootstrap over its trials), the RTF at that count
    (mean of its trials), the RTF curve (mean RTF per ball count), and the balls lost to a
    diverged (NaN) state."""
    board = BoardSpec.load("paper")
    fidelity = ExperimentConfig(board=board, engines=(engine,), balls=(plan.fidelity_balls,),
                                repetitions=plan.repetitions, seed=seed)
    curve = ExperimentConfig(board=board, engines=(engine,), balls=plan.curve, repetitions=1,
                             seed=seed, max_sim_time=plan.curve_sim_time,
                             max_wall_time=plan.curve_wall_time)
    fidelity_trials = trials_of(sim, engine, fidelity)
    trials = [*fidelity_trials, *trials_of(sim, engine, curve)]
    kept = [board_trial(t) for t in fidelity_trials]
    rtfs: dict[int, list[float]] = {}
    for trial in trials:
        if trial.rtf is not None:
            rtfs.setdefault(trial.balls, []).append(trial.rtf)
    at_count = [t.rtf for t in fidelity_trials if t.rtf is not None]
    measures = card_intervals.board_measures(kept, "board", seed)
    measures["rtf_100"] = card_intervals.mean_measure(at_count) if at_count else None
    return BoardRun(measures, kept, {n: statistics.fmean(v) for n, v in sorted(rtfs.items())},
                    sum(t.lost_by_reason.get("nan", 0) for t in trials),
                    sum(t.balls for t in trials))


def mesh_measures(sim: Client, engine: str, plan: CardPlan, seed: int,
                  trials_of: TrialRunner = local_trials
                  ) -> tuple[dict[str, Measure | None], list[BoardTrial]]:
    """The paper-mesh board's figures, beside the primitives', and its trials."""
    config = ExperimentConfig(board=BoardSpec.load("paper-mesh"), engines=(engine,),
                              balls=(plan.mesh_balls,), repetitions=plan.mesh_repetitions,
                              seed=seed)
    kept = [board_trial(t) for t in trials_of(sim, engine, config)]
    return card_intervals.board_measures(kept, "mesh", seed), kept


def sampled(samples: dict[str, list[float]], mean: tuple[str, ...] = ()
            ) -> dict[str, Measure | None]:
    """Each figure's median (timings) or mean (telemetry) with its interval."""
    return {k: (card_intervals.mean_measure(v) if k in mean else
                card_intervals.median_measure(v)) if v else None
            for k, v in samples.items()}


def measure_engine(zenoh_client: Client, zmq_client: Client, engine: str, plan: CardPlan,
                   seed: int, card: CardResults, tell: Say, trials_of: TrialRunner
                   ) -> EngineLaws:
    """Every measure of one engine into ``card``; its law records returned."""
    board = BoardSpec.load("paper")
    tell(f"{engine}: footprint")
    measures = sampled(measure.footprint(zmq_client, engine, board, plan.footprint_s),
                       mean=("idle_rss_mb", "idle_cpu_percent", "rtf1_cpu_percent"))
    tell(f"{engine}: round trips and world operations")
    measure.busy_world(zmq_client, engine, board)
    for name, client in (("zenoh", zenoh_client), ("zmq", zmq_client)):
        status_ms, step_ms = measure.round_trips(client, plan.round_trips)
        measures |= sampled({f"status_{name}_ms": status_ms, f"step_{name}_ms": step_ms})
    costs, restore_errors = measure.world_costs(zmq_client, plan.world_ops)
    measures |= sampled(costs)
    tell(f"{engine}: the physical laws")
    laws = run_engine(zmq_client, engine, choose(plan.laws), seed)
    card.laws[engine] = list(laws.checks)
    measures["laws_passed"] = card_intervals.laws_measure(laws.checks)
    tell(f"{engine}: fidelity after calibration")
    measures |= calibrated_measures(zmq_client, engine, plan, card)
    tell(f"{engine}: the Galton board")
    run = board_measures(zmq_client, engine, plan, seed, trials_of)
    measures |= run.measures
    card.curves[engine] = run.curve
    card.trials[engine] = {"paper": run.trials}
    released = run.released
    if "mesh" in zenoh_client.capabilities().body_shapes:
        tell(f"{engine}: the Galton board as meshes")
        mesh, mesh_trials = mesh_measures(zmq_client, engine, plan, seed, trials_of)
        measures |= mesh
        card.trials[engine]["paper-mesh"] = mesh_trials
        released += sum(t.balls for t in mesh_trials)
    failed = [c for c in laws.checks if c.value is None]
    measures["physics_errors"] = card_intervals.count_measure(
        len(failed) + run.diverged + restore_errors, len(laws.checks) + released + 1)
    notes = card.config.setdefault("notes", [])
    notes += [f"{engine}: law {c.law} did not run: {c.note}" for c in failed]
    if run.diverged:
        notes.append(f"{engine}: {run.diverged} Galton ball(s) lost to a diverged state")
    if restore_errors:
        notes.append(f"{engine}: stepping after restore (board and 100 balls) "
                     "diverged: PHYSICS_ERROR")
    card.measures[engine] = measures
    return laws


def run_card(engines: Sequence[str], plan: CardPlan, seed: int = 0, timeout: float = 30.0,
             say: Say | None = None, trials_of: TrialRunner = local_trials
             ) -> tuple[CardResults, LawResults]:
    """Every measure of every engine, each engine on a daemon of its own; the Galton
    trials through ``trials_of`` (``report-card --pool``: over a pool)."""
    card = CardResults(measures={}, config={"plan": plan.describe(), "seed": seed})
    law_records = []
    tell = say or (lambda _: None)
    for engine in engines:
        began = time.perf_counter()
        with engine_daemon(engine, timeout) as (zenoh_client, zmq_client):
            caps = zenoh_client.capabilities()
            card.versions[engine] = caps.engine_version
            card.config.setdefault("host", caps.host)
            law_records.append(measure_engine(zenoh_client, zmq_client, engine, plan, seed,
                                              card, tell, trials_of))
        tell(f"{engine}: done in {time.perf_counter() - began:.0f} s")
    return card, LawResults(law_records, {"engines": list(engines),
                                          "laws": [e.key for e in choose(plan.laws)],
                                          "seed": seed})


def write_report_card(card: CardResults, laws: LawResults, out: Path,
                      rules: Rules | None = None) -> dict[str, Path]:
    """The card's files in ``out`` and the laws' report in ``out/laws``, linked from the
    card (its plots inlined in the card's HTML page too)."""
    from galton.analysis.laws_report import write_law_outputs
    from galton.analysis.report_card_outputs import write_card_outputs

    written = write_law_outputs(laws, out / "laws")
    links = [path.relative_to(out).as_posix() for key, path in written.items()
             if key != "results_json"]
    return {**write_card_outputs(card, out, rules, law_links=links),
            **{f"laws/{key}": path for key, path in written.items()}}
