"""The state stream and the live view: what they cost a playing world (issue 41).

Usage: python benchmarks/view_stream.py [--seconds 10] [--rounds 3] [--engine mujoco]
       [--json FILE] [--sample-only] [--paced]

1. The view: 500 spheres resting on a plane, ``play(1.0)``, and the page of
   ``galton-client view`` (LiveView, in this process, its viser server serving no browser)
   following the world at 20 Hz for ``--seconds``. Reported: the achieved RTF (Δsim / Δwall
   between the first and last telemetry samples, the daemon's clocks) and the page's draws
   per second. Targets: RTF within ±2 % of 1.0, 20 draws a second.
2. The stream's cost: 1,000 spheres resting on a plane, ``play(0)`` (as fast as the engine
   goes); sim seconds per wall second without a stream and with a 60 Hz stream of all
   1,000 bodies read by a client, in alternating windows (``--rounds`` pairs): the cost is
   the median of the pairs' ratios, with their interquartile range. Target: ≤ 2 %.
3. What one sample costs the physics thread, in the daemon's own code in this process: the
   time of a sample of 1,000 poses (the stream's path: its cached reader, the check, the
   packing) over the time of one step of the same world, both medians of alternating
   batches. A ratio of two timings taken side by side holds on a loaded machine; the
   stream's share of a playing world is then 60 x that ratio x one step's wall time.
4. ``--paced`` (instead of 1 and 2): the target as the issue words it, a playing world: the
   1,000 spheres played at RTF 1.0, the achieved RTF in windows without and with a 60 Hz
   stream of all of them, alternating (``--rounds`` pairs). An engine whose step leaves the
   physics thread idle part of each wall second pays for the stream out of that idle time;
   one that cannot hold RTF 1.0 with this world even without a stream is reported as such.
"""

from __future__ import annotations

import argparse
import socket
import statistics
import threading
import time

import numpy as np
from common import daemon_client, machine, write_json

from galton.client import Client, plane, spheres

RADIUS = 0.05


def _grid(count: int) -> np.ndarray:
    side = int(np.ceil(np.sqrt(count)))
    index = np.arange(count)
    return np.stack([(index % side) * 3 * RADIUS, (index // side) * 3 * RADIUS,
                     np.full(count, RADIUS)], axis=1)


def _scene(sim: Client, count: int) -> None:
    sim.spawn(plane(), spheres([f"b{i:04d}" for i in range(count)], _grid(count),
                               radius=RADIUS, tags=["red"]))
    sim.run_until(0.5)  # settled on the plane


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def view_at_rtf_one(engine: str, seconds: float) -> dict[str, float]:
    import viser

    from galton.client.view.live import LiveView
    with daemon_client(engine) as (daemon, sim):
        _scene(sim, 500)
        server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
        with Client(daemon.instance, daemon.endpoint) as client:
            page = LiveView(client, server, rate=20.0, operator=False)
            draws = [0]
            drawing = page.live.draw

            def counted() -> object:
                sample = drawing()
                draws[0] += sample is not None
                return sample
            page.live.draw = counted  # type: ignore[method-assign]
            stop = threading.Event()
            runner = threading.Thread(target=page.run, args=(stop,))
            runner.start()
            with sim.telemetry(timeout=5) as stream:
                sim.play(1.0)
                first = next(s for s in stream if s.state == "playing" and s.sim_time > 0.5)
                drawn_before = draws[0]
                for last in stream:
                    if last.wall_time - first.wall_time >= seconds:
                        break
                drawn = draws[0] - drawn_before
            sim.pause()
            stop.set()
            runner.join()
            page.close()
        server.stop()
    wall = last.wall_time - first.wall_time
    return {"achieved_rtf": (last.sim_time - first.sim_time) / wall,
            "draws_per_s": drawn / wall, "seconds": wall}


def _speed(sim: Client, seconds: float) -> float:
    """Sim seconds per wall second over a window of a world playing flat out."""
    start, started = sim.status().sim_time, time.monotonic()
    threading.Event().wait(seconds)  # a measurement window, not a synchronisation
    return (sim.status().sim_time - start) / (time.monotonic() - started)


def _paired_windows(engine: str, rtf: float, seconds: float, rounds: int
                    ) -> tuple[list[float], list[float], list[float]]:
    """1,000 bodies played at ``rtf`` (0: flat out): sim seconds per wall second in
    alternating windows without and with a 60 Hz stream of all of them, and the samples a
    second the stream delivered. A paced world's first second (the pacer starting) is not
    measured."""
    without, with_stream, received = [], [], []
    with daemon_client(engine) as (_, sim):
        _scene(sim, 1000)
        sim.play(rtf)
        try:
            if rtf > 0:
                _speed(sim, 1.0)
            for _ in range(rounds):
                without.append(_speed(sim, seconds))
                samples: list[object] = []
                with sim.stream_states(rate=60.0, callback=samples.append):
                    with_stream.append(_speed(sim, seconds))
                received.append(len(samples) / seconds)
        finally:
            sim.pause()
    return without, with_stream, received


def stream_cost(engine: str, seconds: float, rounds: int) -> dict[str, float]:
    """The stream's cost as the median of paired ratios: each round measures a window
    without a stream and the next with one, so a drift of the machine's speed between
    rounds cancels within each pair (single flat-out windows here varied by ±15 %)."""
    without, with_stream, received = _paired_windows(engine, 0.0, seconds, rounds)
    ratios = sorted(w / b for w, b in zip(with_stream, without, strict=True))
    quartiles = (statistics.quantiles(ratios, n=4, method="inclusive")
                 if len(ratios) >= 2 else ratios * 3)
    return {"speed_without": statistics.median(without),
            "speed_with": statistics.median(with_stream),
            "cost_percent": 100 * (1 - statistics.median(ratios)),
            "cost_percent_iqr": [100 * (1 - quartiles[2]), 100 * (1 - quartiles[0])],
            "samples_per_s": statistics.median(received), "rounds": rounds}


def paced_cost(engine: str, seconds: float, rounds: int) -> dict[str, float]:
    """Achieved RTF of 1,000 bodies played at RTF 1.0, without and with a 60 Hz stream."""
    without, with_stream, received = _paired_windows(engine, 1.0, seconds, rounds)
    return {"rtf_without": statistics.median(without), "rtf_with": statistics.median(with_stream),
            "rtf_without_min": min(without), "rtf_with_min": min(with_stream),
            "samples_per_s": statistics.median(received), "rounds": rounds}


def sample_in_steps(engine: str, rounds: int) -> dict[str, float]:
    """Median time of one stream sample over that of one step (item 3 of the docstring)."""
    from galton.daemon.engines import create_engine
    from galton.daemon.world import state_streams as streams
    from galton.daemon.world.world import World

    world = World(create_engine(engine))
    world.spawn([plane(), spheres([f"b{i:04d}" for i in range(1000)], _grid(1000),
                                       radius=RADIUS)])
    world.step(250)
    stream = streams.StateStream("bench", "bench", None, None, 1 / 60, 0.0)
    shared: dict[tuple[int, int, tuple[str, ...] | None], bytes] = {}

    def sample() -> None:
        world.verified_step = -1  # as between the loop's checks
        shared.clear()
        reading = streams._reading(stream, world)
        streams._pack_sample({"stream": "bench", "seq": 1,
                              "poses": streams._pose_bytes(world, reading)},
                             reading.packed_names)
    steps, samples = [], []
    for _ in range(rounds * 10):
        started = time.perf_counter()
        world.step(10)
        steps.append((time.perf_counter() - started) / 10)
        started = time.perf_counter()
        for _ in range(10):
            sample()
        samples.append((time.perf_counter() - started) / 10)
    world.engine.close()
    step, one = statistics.median(steps), statistics.median(samples)
    return {"step_s": step, "sample_s": one, "sample_in_steps": one / step}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--json")
    parser.add_argument("--sample-only", action="store_true",
                        help="only item 3 (in-process, no daemon)")
    parser.add_argument("--paced", action="store_true",
                        help="items 3 and 4: 1,000 bodies at RTF 1.0, without and with a stream")
    args = parser.parse_args()
    sample = sample_in_steps(args.engine, args.rounds)
    print(f"one sample of 1,000 poses: {sample['sample_s'] * 1e6:.0f} us = "
          f"{sample['sample_in_steps']:.3f} steps of that world ({sample['step_s'] * 1e6:.0f} "
          f"us); at 60 Hz: {60 * sample['sample_s'] * 100:.2f} % of the physics thread")
    if args.sample_only:
        write_json(args.json, {"sample": sample, "engine": args.engine})
        return
    if args.paced:
        paced = paced_cost(args.engine, args.seconds, args.rounds)
        print(f"# 1,000 bodies at RTF 1.0 on {machine()}, {args.engine}: achieved RTF "
              f"{paced['rtf_without']:.4f} without a stream (lowest window "
              f"{paced['rtf_without_min']:.4f}), {paced['rtf_with']:.4f} with a 60 Hz stream "
              f"(lowest {paced['rtf_with_min']:.4f}; {paced['samples_per_s']:.1f} samples/s "
              f"received; medians of {paced['rounds']} windows each)")
        write_json(args.json, {"paced": paced, "sample": sample, "engine": args.engine})
        return
    view = view_at_rtf_one(args.engine, args.seconds)
    cost = stream_cost(args.engine, args.seconds, args.rounds)
    print(f"# view and state stream on {machine()}, {args.engine}")
    print(f"500 bodies at RTF 1.0 with the page at 20 Hz: achieved RTF "
          f"{view['achieved_rtf']:.4f}, {view['draws_per_s']:.1f} draws/s")
    print(f"1,000 bodies flat out: {cost['speed_without']:.3f} sim s/s without a stream, "
          f"{cost['speed_with']:.3f} with 60 Hz ({cost['samples_per_s']:.1f} samples/s "
          f"received): cost {cost['cost_percent']:.2f} % (median of {cost['rounds']} paired "
          f"rounds; interquartile {cost['cost_percent_iqr'][0]:.2f} to "
          f"{cost['cost_percent_iqr'][1]:.2f} %)")
    write_json(args.json, {"view": view, "stream_cost": cost, "sample": sample,
                           "engine": args.engine})


if __name__ == "__main__":
    main()
