"""Is MuJoCo's physics itself slower inside the daemon? mj_step's wall and CPU time per trial,
through a daemon and in-process, for the same bit-identical trial.

Usage: python benchmarks/physics_cpu.py [--balls 100] [--trials 10] [--params JSON]
                                        [--daemon-args "..."] [--own-thread] [--json FILE]

A daemon is started by this script (``--serve``) with ``mujoco.mj_step`` wrapped by a timer
that adds up its wall time (``perf_counter``) and the calling thread's CPU time
(``thread_time``); this process wraps its own ``mj_step`` the same way and runs the in-process
loop of ``benchmarks/bridge_overhead.py``. Trials alternate between the two. Where the
daemon's CPU time per trial is higher than in-process for the same work, the physics itself
runs slower there (not a wait for the GIL, which CPU time does not count).
``--daemon-args`` passes options to the daemon (e.g. "--telemetry-rate 0").
``--own-thread`` serves with the physics loop on a thread started for it (``Daemon.start``,
how galton-daemon ran until 2026-11-24) instead of galton-daemon's main thread: the same
MuJoCo trial then cost about 4 % more CPU in ``mj_step`` (docs/PERFORMANCE.md).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import mujoco
from bridge_overhead import trial_config, wall
from common import machine, write_json
from local_sim import LocalSim

from galton.client import Client
from galton.client.sdk.embedded import free_loopback_port

INSTANCE = "physics-cpu"


class StepTimer:
    """Wraps mujoco.mj_step in this process: calls, wall and thread CPU seconds."""

    def __init__(self) -> None:
        self.calls, self.wall, self.cpu = 0, 0.0, 0.0
        original = mujoco.mj_step

        def timed(m: Any, d: Any, nstep: int = 1) -> None:
            started, cpu = time.perf_counter(), time.thread_time()
            original(m, d, nstep)
            self.cpu += time.thread_time() - cpu
            self.wall += time.perf_counter() - started
            self.calls += 1
        mujoco.mj_step = timed

    def totals(self) -> dict[str, float]:
        return {"calls": self.calls, "wall_s": self.wall, "cpu_s": self.cpu}


def serve_on_own_thread(options: Any, announce: Any = print) -> int:
    """run_daemon as it was before 2026-11-24: the physics loop on a thread of its own,
    the main thread waiting for SIGINT/SIGTERM."""
    from galton.daemon.server import Daemon, signal_wakeup_pipe
    wake_read = signal_wakeup_pipe()
    daemon = Daemon(options)
    daemon.start()
    announce("galton-daemon ready: physics loop on its own thread")
    os.read(wake_read, 1)
    daemon.close()
    return 0


def serve(report: str, own_thread: bool, daemon_args: list[str]) -> None:
    """The daemon side: galton-daemon's own entry point, with mj_step timed; the totals are
    written to ``report`` when it shuts down."""
    timer = StepTimer()
    from galton.daemon import cli, server
    if own_thread:
        cli.run_daemon = serve_on_own_thread  # type: ignore[assignment]

    close = server.Daemon.close

    def close_and_report(daemon: server.Daemon) -> None:
        Path(report).write_text(json.dumps(timer.totals()))
        close(daemon)
    server.Daemon.close = close_and_report  # type: ignore[method-assign]
    sys.argv = ["galton-daemon", *daemon_args]
    cli.main()


def measure(balls: int, trials: int, params: dict[str, Any] | None,
            daemon_args: list[str], own_thread: bool = False) -> dict[str, Any]:
    timer = StepTimer()
    endpoint = f"tcp/127.0.0.1:{free_loopback_port()}"
    report = Path(f"/tmp/physics_cpu_{endpoint.rsplit(':', 1)[-1]}.json")
    args = ["--engine", "mujoco", "--instance", INSTANCE, "--listen", endpoint, *daemon_args]
    daemon = subprocess.Popen([sys.executable, __file__, "--serve", str(report),
                               "own" if own_thread else "main", "--",
                               *args], stdout=subprocess.PIPE, text=True)
    assert daemon.stdout is not None
    daemon.stdout.readline()  # "galton-daemon ready: ..."
    config = trial_config("mujoco", balls, params)
    local_walls, bridge_walls = [], []
    try:
        with Client(INSTANCE, endpoint, timeout=120) as sim:
            for _ in range(trials):
                local_walls.append(wall(LocalSim(), config)[0])
                bridge_walls.append(wall(sim, config)[0])
    finally:
        daemon.send_signal(2)
        daemon.wait(30)
    served = json.loads(report.read_text())
    report.unlink()
    local = timer.totals()
    per_trial = {side: {k: v / trials for k, v in totals.items()}
                 for side, totals in (("in_process", local), ("daemon", served))}
    return {"balls": balls, "trials": trials, "params": params or {},
            "daemon_args": daemon_args, "own_thread": own_thread, "per_trial": per_trial,
            "wall_median_s": {"in_process": statistics.median(local_walls),
                              "daemon": statistics.median(bridge_walls)}}


def main() -> None:
    if len(sys.argv) > 2 and sys.argv[1] == "--serve":
        serve(sys.argv[2], sys.argv[3] == "own", sys.argv[5:])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, default=100)
    parser.add_argument("--trials", type=int, default=10)
    parser.add_argument("--params", default="{}", help="daemon parameters as JSON")
    parser.add_argument("--daemon-args", default="")
    parser.add_argument("--own-thread", action="store_true",
                        help="physics loop on its own thread, as before 2026-11-24")
    parser.add_argument("--json")
    args = parser.parse_args()
    result = measure(args.balls, args.trials, json.loads(args.params) or None,
                     shlex.split(args.daemon_args), args.own_thread)
    print(f"# mj_step per trial on {machine()}: paper board, {args.balls} balls, "
          f"{args.trials} alternating trials")
    print("| side | trial wall median (s) | mj_step calls | mj_step wall (ms) | "
          "mj_step thread CPU (ms) |\n| --- | --- | --- | --- | --- |")
    for side in ("in_process", "daemon"):
        t = result["per_trial"][side]
        print(f"| {side} | {result['wall_median_s'][side]:.3f} | {t['calls']:.0f} | "
              f"{t['wall_s'] * 1e3:.1f} | {t['cpu_s'] * 1e3:.1f} |")
    write_json(args.json, result)


if __name__ == "__main__":
    main()
