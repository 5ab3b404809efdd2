"""The report card's samples of one daemon: its footprint (idle, and at RTF 1) from its
own telemetry, and what embedding it costs (round trips on each transport, snapshot,
restore, fork, a 1 s prediction), each timed here with a monotonic clock. Every figure is
a list of repeated samples, from which the card makes its value and 95 % interval."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from galton.analysis.board import BoardSpec
from galton.client.bench.build import board_groups
from galton.client.sdk.client import Client, body_group, spheres
from galton.protocol import PhysicsError

BALLS = 100  # resting beside the board, so each step has contacts to solve


def busy_world(sim: Client, engine: str, board: BoardSpec) -> None:
    """A fresh world: the paper board, and 100 of its balls resting on a tray beside it."""
    sim.load_world(engine)
    side = 10
    grid = np.array([[20.0 + (i % side) * 0.1, (i // side) * 0.1, -0.95 + board.ball.radius]
                     for i in range(BALLS)])
    sim.spawn(*board_groups(board, engine),
              body_group("box", (1.0, 1.0, 0.05), ["tray"], [[20.5, 0.5, -1.0]], static=True),
              spheres([f"resting{i}" for i in range(BALLS)], grid, board.ball.radius,
                      mass=board.ball.mass))
    sim.step(200)  # settled on the tray


Samples = dict[str, list[float]]
PREDICTIONS = 5  # at least: fewer samples give no 95 % interval of their median


def telemetry_samples(sim: Client, seconds: float) -> tuple[list[float], list[float]]:
    """The CPU % and RSS (MB) samples the daemon reports over ``seconds`` of telemetry."""
    cpu: list[float] = []
    rss: list[float] = []
    with sim.telemetry(timeout=5) as stream:
        first = next(stream)
        for sample in stream:
            cpu.append(sample.cpu_percent)
            rss.append(sample.rss_bytes / 1e6)
            if sample.wall_time - first.wall_time >= seconds:
                break
    return cpu, rss


def footprint(sim: Client, engine: str, board: BoardSpec, seconds: float) -> Samples:
    """Idle (board loaded, paused) CPU and RSS, then CPU while playing at RTF 1."""
    sim.load_world(engine)
    sim.spawn(*board_groups(board, engine))
    sim.step(10)
    idle_cpu, idle_rss = telemetry_samples(sim, seconds)
    busy_world(sim, engine, board)
    sim.play(1.0)
    try:
        played_cpu, _ = telemetry_samples(sim, seconds)
    finally:
        sim.pause()
    return {"idle_rss_mb": idle_rss, "idle_cpu_percent": idle_cpu,
            "rtf1_cpu_percent": played_cpu}


def times_ms(action: Callable[[], object], count: int) -> list[float]:
    """The wall time of each of ``count`` calls, in ms (after one untimed call)."""
    action()
    times = []
    for _ in range(count):
        began = time.perf_counter()
        action()
        times.append(time.perf_counter() - began)
    return [1000.0 * t for t in times]


def round_trips(sim: Client, count: int) -> tuple[list[float], list[float]]:
    """status and step(1) round trips (ms each) on a busy paused world."""
    return times_ms(sim.status, count), times_ms(lambda: sim.step(1), count)


def world_costs(sim: Client, count: int) -> tuple[Samples, int]:
    """snapshot, fork (and delete), a 1 s prediction and restore, ms each; then the
    steps after the restores must run. Returns the costs and the physics errors met (a
    world that diverged is reset to its created state, so the card goes on)."""
    sim.snapshot("card")
    forks = iter(range(10**6))

    def fork() -> None:
        name = f"card-fork-{next(forks)}"
        sim.fork_world(name)
        sim.delete_world(name)
    costs = {
        "snapshot_ms": times_ms(lambda: sim.snapshot("card"), count),
        "fork_ms": times_ms(fork, count),
        "predict_ms": times_ms(lambda: sim.predict(1.0, timeout=60),
                               max(min(PREDICTIONS, count), count // 3)),
        "restore_ms": times_ms(lambda: sim.restore("card"), count)}
    sim.delete_snapshot("card")
    try:
        sim.step(50)
    except PhysicsError:
        sim.reset("state")
        return costs, 1
    return costs, 0
