"""Real-time pacing: play at a target RTF with the physics loaded, and keep telemetry.

Usage: python benchmarks/pacing.py [--seconds 30] [--rtf 1.0] [--balls 100] [--json FILE]

The paper board with ``--balls`` balls released at once, then ``play(rtf)`` for
``--seconds`` of wall time. The achieved RTF is Δsim / Δwall between the first and the
last telemetry sample of the window (the daemon's clocks); the telemetry rate is the
samples received per wall second against the configured 10 Hz, and gaps in ``seq`` count
samples dropped. Target (issue 6): achieved RTF within ±2 % of 1.0 over 30 s, telemetry
kept at its rate.
"""

from __future__ import annotations

import argparse

from common import ENGINES, daemon_client, machine, write_json

from galton.analysis.board import BallSpec, BoardSpec
from galton.analysis.board_release import release_schedule
from galton.client.bench.build import ball_group, ball_names, board_groups

TELEMETRY_HZ = 10.0


def measure(engine: str, seconds: float, rtf: float, balls: int) -> dict:
    board = BoardSpec.load("paper")
    board = board.replace(ball=BallSpec(board.ball.radius, board.ball.mass, balls))
    with daemon_client(engine, telemetry_rate=TELEMETRY_HZ) as (_, sim):
        sim.load_world(engine, board.engine_contacts(engine).params or None)  # its settings
        sim.spawn(*board_groups(board, engine))
        sim.spawn(ball_group(board, engine, ball_names(balls),
                             release_schedule(board, 0, balls).positions))
        with sim.telemetry(timeout=5) as stream:
            sim.play(rtf)
            first = next(s for s in stream if s.state == "playing" and s.sim_time > 0)
            samples = [first]
            for sample in stream:
                samples.append(sample)
                if sample.wall_time - first.wall_time >= seconds:
                    break
        sim.pause()
    last = samples[-1]
    wall = last.wall_time - first.wall_time
    achieved = (last.sim_time - first.sim_time) / wall
    dropped = (last.seq - first.seq + 1) - len(samples)
    return {"engine": engine, "target_rtf": rtf, "seconds": wall, "achieved_rtf": achieved,
            "error_percent": 100 * (achieved - rtf) / rtf,
            "telemetry_hz": (len(samples) - 1) / wall, "telemetry_dropped": dropped,
            "cpu_percent_mean": sum(s.cpu_percent for s in samples) / len(samples)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--rtf", type=float, default=1.0)
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--json")
    args = parser.parse_args()
    results = [measure(e, args.seconds, args.rtf, args.balls) for e in ENGINES]
    print(f"# pacing on {machine()}: paper board, {args.balls} balls, target RTF {args.rtf}, "
          f"{args.seconds:g} s")
    print("| engine | achieved RTF | error | telemetry rate (Hz) | samples dropped | "
          "daemon CPU (%) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for r in results:
        print(f"| {r['engine']} | {r['achieved_rtf']:.4f} | {r['error_percent']:+.2f} % | "
              f"{r['telemetry_hz']:.2f} | {r['telemetry_dropped']} | "
              f"{r['cpu_percent_mean']:.1f} |")
    write_json(args.json, results)


if __name__ == "__main__":
    main()
