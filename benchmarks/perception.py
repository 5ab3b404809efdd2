"""Rendering, ray casts and a camera stream beside a playing world (issue 26).

Usage: python benchmarks/perception.py [--renders 30] [--rays 10000] [--ray-repeats 50]
                                       [--stream-seconds 10] [--engines mujoco,pybullet]
                                       [--json FILE]

The scene is the paper board with 100 balls resting in its bins; the camera faces the board
(client/bench/picture.py), 640 × 480.
(a) RGB + depth render: the engine call timed in this process on a World like the daemon's,
    and the whole ``render`` request (raw) through a daemon on loopback. Target ≤ 100 ms.
(b) 10,000 rays from in front of the glass into the board: the engine call in process
    (target ≤ 10 ms) and the ``raycast`` request through the daemon.
(c) the world playing at RTF 1.0 for ``--stream-seconds`` of wall time, first alone, then
    with a 10 Hz 640 × 480 RGB + depth camera stream; meanwhile a control client reads 10
    balls' states at 100 Hz. Reported: the achieved RTF (telemetry's Δsim / Δwall; target
    within ±2 %) and the control call's p50 / p99, with and without the stream.
"""

from __future__ import annotations

import argparse
import threading
import time
from typing import Any

import numpy as np
from common import (
    ENGINES,
    daemon_client,
    machine,
    p50_p99,
    percentiles_ms,
    timed,
    write_json,
)

from galton.analysis.board import BallSpec, BoardSpec
from galton.analysis.board_release import release_schedule
from galton.client import Client
from galton.client.bench.build import ball_group, ball_names, board_groups
from galton.client.bench.picture import board_camera
from galton.daemon.engines import create_engine
from galton.daemon.world.cameras import parse_camera, view_of
from galton.daemon.world.world import World

SIZE = (640, 480)
BALLS = 100
SETTLE_S = 6.0  # sim seconds for the released balls to reach the bins
STREAM_HZ, CONTROL_HZ = 10.0, 100.0
SEED = 26


def scene(engine: str) -> tuple[BoardSpec, list[Any]]:
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, BALLS))
    balls = ball_group(board, engine, ball_names(BALLS),
                       release_schedule(board, 0, BALLS).positions)
    return board, [*board_groups(board, engine), balls]


def camera_map(board: BoardSpec) -> dict[str, Any]:
    return {**board_camera(board, SIZE), "outputs": ["rgb", "depth"]}


def rays(board: BoardSpec, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Seeded rays from a plane in front of the glass into the board's cavity."""
    rng = np.random.default_rng(SEED)
    half = board.walls.inner_x
    origins = np.column_stack([rng.uniform(-half, half, count), np.full(count, -3.0),
                               rng.uniform(0.1, board.walls.height, count)])
    directions = np.column_stack([rng.normal(0, 0.1, count), np.ones(count),
                                  rng.normal(0, 0.1, count)])
    return origins, directions / np.linalg.norm(directions, axis=1)[:, None]


# -- (a) and (b) in process -------------------------------------------------------------
def in_process(engine: str, renders: int, count: int, repeats: int) -> dict[str, Any]:
    board, groups = scene(engine)
    world = World(create_engine(engine))
    try:
        if board.engine_contacts(engine).params:  # the board's settings, as the bench sets
            world.engine.set_params(board.engine_contacts(engine).params)
        world.spawn(groups)
        world.step(round(SETTLE_S / world.engine.timestep))
        view = view_of(world, parse_camera(camera_map(board), "camera"))
        world.engine.render([view])  # warm up (contexts, buffers)
        render = timed(lambda: world.engine.render([view]), renders)
        origins, directions = rays(board, count)
        world.engine.raycast(origins, directions, 100.0)
        cast = timed(lambda: world.engine.raycast(origins, directions, 100.0), repeats)
        hits = int(np.sum(world.engine.raycast(origins, directions, 100.0)[0]))
    finally:
        world.engine.close()
    return {"render_engine": percentiles_ms(render), "rays_engine": percentiles_ms(cast),
            "ray_hits": hits}


# -- (a) and (b) through the daemon, (c) the stream -------------------------------------
def settled_scene(sim: Client, engine: str) -> BoardSpec:
    board, groups = scene(engine)
    if board.engine_contacts(engine).params:  # the board's settings, as the bench sets
        sim.set_params(board.engine_contacts(engine).params)
    sim.spawn(*groups)
    sim.run_until(SETTLE_S)
    return board


def through_daemon(sim: Client, board: BoardSpec, renders: int, count: int,
                   repeats: int) -> dict[str, Any]:
    view = camera_map(board)
    sim.render(view)
    render = timed(lambda: sim.render(view), renders)
    origins, directions = rays(board, count)
    sim.raycast(origins, directions=directions)
    cast = timed(lambda: sim.raycast(origins, directions=directions), repeats)
    return {"render_daemon": percentiles_ms(render), "rays_daemon": percentiles_ms(cast)}


def playing(sim: Client, board: BoardSpec, seconds: float, stream: bool) -> dict[str, Any]:
    """Play at RTF 1.0 for ``seconds``; control reads at 100 Hz, a 10 Hz camera if asked."""
    stop = threading.Event()
    control: list[float] = []
    frames: list[float] = []
    watched = ball_names(10)

    def paced(rate: float, action: Any, into: list[float]) -> None:
        start, k = time.perf_counter(), 0
        while not stop.is_set():
            stop.wait(max(0.0, start + k / rate - time.perf_counter()))
            if stop.is_set():
                return
            sent = time.perf_counter()
            action()
            into.append(time.perf_counter() - sent)
            k += 1

    view = camera_map(board)
    workers = [threading.Thread(target=paced, args=(CONTROL_HZ, lambda: sim.get_states(
        watched), control))]
    if stream:
        workers.append(threading.Thread(target=paced, args=(STREAM_HZ, lambda: sim.render(
            view), frames)))
    with sim.telemetry(timeout=5) as telemetry:
        sim.play(1.0)
        first = next(s for s in telemetry if s.state == "playing" and s.sim_time > 0)
        for worker in workers:
            worker.start()
        last = first
        for sample in telemetry:
            last = sample
            if sample.wall_time - first.wall_time >= seconds:
                break
        stop.set()
    for worker in workers:
        worker.join()
    sim.pause()
    rtf = (last.sim_time - first.sim_time) / (last.wall_time - first.wall_time)
    found = {"rtf": rtf, "rtf_error_percent": 100 * (rtf - 1.0), "control": percentiles_ms(
        control)}
    return found | ({"frames": percentiles_ms(frames)} if stream else {})


def measure(engine: str, args: argparse.Namespace) -> dict[str, Any]:
    result: dict[str, Any] = {"engine": engine, **in_process(
        engine, args.renders, args.rays, args.ray_repeats)}
    with daemon_client(engine, telemetry_rate=20.0) as (_daemon, sim):
        board = settled_scene(sim, engine)
        result["render_backend"] = sim.capabilities().render_backend
        result |= through_daemon(sim, board, args.renders, args.rays, args.ray_repeats)
        result["alone"] = playing(sim, board, args.stream_seconds, stream=False)
        result["with_stream"] = playing(sim, board, args.stream_seconds, stream=True)
    return result


def print_tables(results: list[dict[str, Any]], args: argparse.Namespace) -> None:
    print(f"# perception on {machine()}, {time.strftime('%Y-%m-%d')}: paper board, {BALLS} "
          f"balls in the bins, {SIZE[0]}x{SIZE[1]}")
    print(f"| engine (back end) | RGB + depth render: engine call p50 / p99 | through the "
          f"daemon p50 / p99 | {args.rays} rays: engine call p50 / p99 | through the daemon "
          "p50 / p99 |")
    print("| --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} ({r['render_backend']}) | {_pair(r['render_engine'])} | "
              f"{_pair(r['render_daemon'])} | {_pair(r['rays_engine'])} | "
              f"{_pair(r['rays_daemon'])} |")
    print(f"\n| engine | RTF alone | RTF with a {STREAM_HZ:g} Hz camera | control call "
          "p50 / p99 alone | with the camera | camera frame p50 / p99 |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in results:
        alone, streamed = r["alone"], r["with_stream"]
        print(f"| {r['engine']} | {alone['rtf']:.4f} ({alone['rtf_error_percent']:+.2f} %) | "
              f"{streamed['rtf']:.4f} ({streamed['rtf_error_percent']:+.2f} %) | "
              f"{_pair(alone['control'])} | {_pair(streamed['control'])} | "
              f"{_pair(streamed['frames'])} |")
    print(f"\n({args.renders} renders, {args.ray_repeats} ray batches "
          + ", ".join(f"{r['engine']} {r['ray_hits']} hits" for r in results)
          + f"; {args.stream_seconds:g} s of play each; control: get_states of 10 balls at "
          f"{CONTROL_HZ:g} Hz)")


def _pair(p: dict[str, Any]) -> str:
    return f"{p50_p99(p, 2)} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--renders", type=int, default=30)
    parser.add_argument("--rays", type=int, default=10_000)
    parser.add_argument("--ray-repeats", type=int, default=50)
    parser.add_argument("--stream-seconds", type=float, default=10.0)
    parser.add_argument("--engines", default=",".join(ENGINES))
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(engine, args) for engine in args.engines.split(",")]
    print_tables(results, args)
    write_json(args.json, results)


if __name__ == "__main__":
    main()
