"""One Galton trial through the bridge: build the board, release the balls, run until
every ball has settled or the sim-time cap, read all balls in one call, score them."""

from __future__ import annotations

import threading
import time
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from galton.analysis.board import BoardSpec
from galton.analysis.board_release import Perturbation, perturbation
from galton.analysis.board_scoring import DEFAULT_SETTLE_SPEED, BallOutcomes, classify_balls
from galton.analysis.records import TrialRecord
from galton.client.bench.build import ball_group, ball_names, board_groups
from galton.client.bench.defaults import DEFAULT_MAX_SIM_TIME_S
from galton.client.sdk.client import Client, States
from galton.client.sdk.recording import Recorder
from galton.protocol import Telemetry
from galton.protocol.operations import LONG_RUNNING_TIMEOUT_S

DEFAULT_CHECK_INTERVAL_S = 0.5
# The daemon checks for rest every check interval; the bench looks itself at least this
# often, so a lost ball falling for ever (never at rest) stops the trial within this much
# sim time.
SETTLE_SEGMENT_S = 10.0
# ... and sizes each settling request to take about this much wall time at the RTF the
# trial has run at so far, so that a slow engine's request (DART at 1,000 balls runs at
# RTF ~0.01) stays far inside a client's 600 s wait. The first segment is a short probe.
SEGMENT_WALL_S = 60.0
FIRST_SEGMENT_S = 1.0
FIRST_REQUEST_WAIT_S = 6 * 3600.0
# An RTF-only trial (max_wall_time) advances in chunks of about WALL_CHUNK_S of wall time,
# after a probe of PROBE_S of sim time; never under MIN_CHUNK_S (one step at 1 ms).
WALL_CHUNK_S = 5.0
PROBE_S = 0.01
MIN_CHUNK_S = 0.001


@dataclass
class TrialConfig:
    """What one trial runs: an engine, a board (ball count and release mode in it)."""

    engine: str
    board: BoardSpec
    repetition: int = 0
    seed: int = 0
    max_sim_time: float = DEFAULT_MAX_SIM_TIME_S
    check_interval: float = DEFAULT_CHECK_INTERVAL_S
    settle_speed: float = DEFAULT_SETTLE_SPEED
    # Where to save a recording of the trial that `galton-client view` replays (None: none).
    recording: Path | None = None
    # For a trial that measures only the RTF: stop after this much wall time of physics,
    # settled or not (None: run until the balls rest or max_sim_time).
    max_wall_time: float | None = None

    @property
    def balls(self) -> int:
        return self.board.ball.count


@dataclass
class Footprint:
    """The daemon's CPU and memory as its telemetry reported them during a trial."""

    cpu: list[float] = field(default_factory=list)
    peak_rss: int = 0
    lock: threading.Lock = field(default_factory=threading.Lock)

    def add(self, sample: Telemetry) -> None:
        with self.lock:
            if sample.state != "stopped":
                self.cpu.append(sample.cpu_percent)
            self.peak_rss = max(self.peak_rss, sample.peak_rss_bytes)

    def cpu_mean(self) -> float | None:
        with self.lock:
            return float(np.mean(self.cpu)) if self.cpu else None


class PhysicsClock:
    """Wall time spent inside physics requests, summed: the denominator of the RTF."""

    def __init__(self, sim: Client) -> None:
        self.sim = sim
        self.wall = 0.0
        # Where the last physics request left the world: a trial's world starts at 0 and
        # moves only by these requests, so this is also the sim time they ran.
        self.sim_time = 0.0

    def segment(self, check_interval: float) -> float:
        """The sim time of the next settling request (settling_segment)."""
        return settling_segment(self.wall, self.sim_time, check_interval)

    def run_until(self, sim_time: float) -> float:
        started = time.perf_counter()
        stamp = self.sim.run_until(sim_time, timeout=self.wait_for(sim_time))
        self._count(started, stamp.sim_time)
        return stamp.sim_time

    def run_until_rest(self, sim_time: float, names: list[str], speed: float,
                       every: float) -> tuple[States, bool]:
        """Run until these balls rest or ``sim_time``, in one round trip (timed as physics)."""
        started = time.perf_counter()
        states, at_rest = self.sim.run_until_rest(sim_time, names, speed, every,
                                                  timeout=self.wait_for(sim_time))
        self._count(started, states.sim_time)
        return states, at_rest

    def wait_for(self, sim_time: float) -> float:
        """How long a request running the world to ``sim_time`` may take (settling_wait)."""
        return settling_wait(sim_time - self.sim_time, self.wall, self.sim_time)

    def _count(self, started: float, sim_time: float) -> None:
        self.wall += time.perf_counter() - started
        self.sim_time = sim_time


def settling_segment(wall: float, simulated: float, check_interval: float) -> float:
    """About SEGMENT_WALL_S of wall time at the RTF measured so far (``simulated`` s in
    ``wall`` s; a short probe before any), at most SETTLE_SEGMENT_S, in whole check
    intervals: the daemon's rest checks then fall on the same sim times whatever the
    segments, so the trial's outcome does not depend on the machine's speed."""
    if wall <= 0.0 or simulated <= 0.0:
        span = FIRST_SEGMENT_S
    else:
        span = min(SETTLE_SEGMENT_S, SEGMENT_WALL_S * simulated / wall)
    return max(1, int(span / check_interval + 1e-9)) * check_interval


def settling_wait(span: float, wall: float, simulated: float) -> float:
    """The client's wait for a request running ``span`` s of sim time: 10 x what the RTF
    so far predicts, at least the usual 600 s; before any figure, FIRST_REQUEST_WAIT_S (a
    slow engine's first 1 s of a 500-ball crowd may take hours; a daemon that dies is seen
    at once by its liveliness, so the long wait only ever waits on a working daemon)."""
    if wall <= 0.0 or simulated <= 0.0:
        return FIRST_REQUEST_WAIT_S
    return max(LONG_RUNNING_TIMEOUT_S, 10.0 * span * wall / simulated)


def prepare_world(sim: Client, config: TrialConfig) -> tuple[Perturbation, list[str]]:
    """A fresh world on the engine with the board's settings, the board built, no balls yet
    (its bodies carry the board's materials: build.py)."""
    params = config.board.engine_contacts(config.engine).params
    sim.load_world(config.engine, dict(params) or None)
    shake = perturbation(config.board, config.repetition, config.seed, config.balls)
    sim.spawn(*board_groups(config.board, config.engine, shake.board_offset_x))
    return shake, ball_names(config.balls)


def release_and_settle(sim: Client, config: TrialConfig, shake: Perturbation,
                       names: list[str], clock: PhysicsClock) -> BallOutcomes:
    """Release the balls (all at once, or each at its time), then run until none moves.

    A ball caught at the top of a bounce on a pin looks at rest, and stuck, for one check;
    so balls seen stuck must still be stuck at a later rest before the trial ends.
    """
    released, now = release(sim, config, shake, names, clock)
    stuck_seen = False
    while True:
        if now >= config.max_sim_time - 1e-9:
            return classify(config, shake, sim.get_states(names[:released]))
        states, at_rest = clock.run_until_rest(
            min(now + clock.segment(config.check_interval), config.max_sim_time),
            names[:released], config.settle_speed, config.check_interval)
        now = states.sim_time
        outcomes = classify(config, shake, states)
        if not (at_rest or outcomes.reasons.get("moving", 0) == 0):
            continue
        if outcomes.reasons.get("stuck", 0) == 0 or stuck_seen:
            return outcomes
        stuck_seen = True


def run_for_wall(sim: Client, config: TrialConfig, shake: Perturbation, names: list[str],
                 clock: PhysicsClock, budget: float) -> BallOutcomes:
    """An RTF-only trial: release, then run in chunks sized by the RTF so far (a short
    probe first) until ``budget`` s of physics wall time or max_sim_time; the balls as they
    are then. No request outruns its wait, however slow the engine gets as its crowd forms
    (DART's 500-ball funnel runs at RTF 0.0003)."""
    released, now = release(sim, config, shake, names, clock)
    while now < config.max_sim_time - 1e-9 and clock.wall < budget:
        span = wall_chunk(budget - clock.wall, clock.wall, clock.sim_time)
        now = clock.run_until(min(now + span, config.max_sim_time))
    return classify(config, shake, sim.get_states(names[:released]))


def wall_chunk(remaining: float, wall: float, simulated: float) -> float:
    """Sim seconds expected to take the lesser of ``remaining`` and WALL_CHUNK_S of wall
    time at the RTF so far (PROBE_S before any figure; at least MIN_CHUNK_S)."""
    if wall <= 0.0 or simulated <= 0.0:
        return PROBE_S
    return max(MIN_CHUNK_S, min(remaining, WALL_CHUNK_S) * simulated / wall)


def release(sim: Client, config: TrialConfig, shake: Perturbation, names: list[str],
            clock: PhysicsClock) -> tuple[int, float]:
    """Spawn each ball at its release time; return how many were released, and when."""
    times = shake.release.times
    released, now = 0, 0.0
    while released < len(names):
        ready = int(np.searchsorted(times, now + 1e-9, side="right"))
        sim.spawn(ball_group(config.board, config.engine, names[released:ready],
                             shake.release.positions[released:ready]))
        released = ready
        if released < len(names):
            if times[released] >= config.max_sim_time:
                break
            now = clock.run_until(times[released])
    return released, now


def classify(config: TrialConfig, shake: Perturbation, states: States) -> BallOutcomes:
    """Every released ball's state, classified against the board."""
    return classify_balls(config.board, states.positions, states.speeds,
                          shake.board_offset_x, config.settle_speed)


def run_trial(sim: Client, config: TrialConfig) -> TrialRecord:
    """Run one trial on the daemon behind ``sim`` and return its record (unscored)."""
    footprint = Footprint()
    with sim.on_telemetry(footprint.add):
        shake, names = prepare_world(sim, config)
        clock = PhysicsClock(sim)
        with _recorded(sim, config.recording):
            outcomes = (release_and_settle(sim, config, shake, names, clock)
                        if config.max_wall_time is None else
                        run_for_wall(sim, config, shake, names, clock, config.max_wall_time))
        sim_time = sim.status().sim_time
        settings = sim.get_params()
        version = sim.capabilities().engine_version
    unreleased = config.balls - len(outcomes.outcomes)
    lost_by_reason = {r: outcomes.reasons.get(r, 0)
                      for r in ("below_floor", "outside_cavity", "tunnelled", "nan")}
    return TrialRecord(
        engine=config.engine, engine_version=version, board=config.board.name,
        balls=config.balls, repetition=config.repetition, seed=config.seed,
        release=config.board.release.mode, counts=[int(c) for c in outcomes.counts],
        settled=outcomes.settled, lost=outcomes.lost, lost_by_reason=lost_by_reason,
        unsettled=outcomes.unsettled + unreleased, sim_time=sim_time, wall_time=clock.wall,
        rtf=sim_time / clock.wall if clock.wall > 0 else None,
        cpu_percent_mean=footprint.cpu_mean(), peak_rss_bytes=footprint.peak_rss or None,
        settings=settings, config=trial_config_dict(config, shake))


def _recorded(sim: Client, path: Path | None) -> AbstractContextManager[object]:
    """A recording of the trial from its built board on (client/view/recording.py)."""
    return nullcontext() if path is None else Recorder(sim, path)


def trial_config_dict(config: TrialConfig, shake: Perturbation) -> dict[str, Any]:
    return {
        "board": config.board.to_dict(), "max_sim_time": config.max_sim_time,
        "check_interval": config.check_interval, "settle_speed": config.settle_speed,
        "board_offset_x": shake.board_offset_x,
        **({} if config.max_wall_time is None else {"max_wall_time": config.max_wall_time}),
    }
