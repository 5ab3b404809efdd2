"""How long a `galton-client` command takes from the shell, beside the floors it cannot go
under: the interpreter alone and typer + rich (issue 33: each command took about 0.9 s).

Usage: python benchmarks/cli_startup.py [--runs 15] [--json FILE]
Each command runs --runs times as a fresh process; medians and minima in seconds. `status`
asks a daemon started here (MuJoCo), so it includes a Zenoh session and one round trip
(neither numpy nor the SDK's Client since issue 47, nor typer and rich into a pipe: the
lean front, client/cli/lean.py); "status (terminal)" runs it with stdout on a
pseudo-terminal, where it draws its table with rich.
"""

from __future__ import annotations

import argparse
import json
import os
import pty
import shutil
import statistics
import subprocess
import sys
import time

from common import daemon_client


def timed(command: list[str], runs: int, terminal: bool = False) -> tuple[float, float]:
    """Median and minimum wall time of ``runs`` fresh runs of ``command``, its stdout a
    pipe or (``terminal``) a pseudo-terminal."""
    times = []
    for _ in range(runs):
        if terminal:
            reader, writer = pty.openpty()
        start = time.perf_counter()
        if terminal:
            subprocess.run(command, check=True, stdout=writer, stderr=subprocess.PIPE)
        else:
            subprocess.run(command, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
        if terminal:  # a status table fits the pseudo-terminal's buffer: nothing blocks
            os.close(writer)
            os.close(reader)
    return statistics.median(times), min(times)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=15)
    parser.add_argument("--json")
    args = parser.parse_args()
    cli = shutil.which("galton-client") or "galton-client"
    python = sys.executable
    rows = {"python -c pass (floor)": [python, "-c", "pass"],
            "import typer, rich (typer CLI floor)": [python, "-c", "import typer, rich.console"],
            "galton-client --version": [cli, "--version"],
            "galton-client --help": [cli, "--help"],
            "galton-client spawn --help": [cli, "spawn", "--help"]}
    found = {name: timed(command, args.runs) for name, command in rows.items()}
    with daemon_client("mujoco") as (daemon, _client):
        status = [cli, "--connect", daemon.endpoint, "--instance", daemon.instance, "status"]
        found["galton-client status"] = timed(status, args.runs)
        found["galton-client status (terminal)"] = timed(status, args.runs, terminal=True)
    print(f"{'command':32} {'median s':>9} {'min s':>7}")
    for name, (median, least) in found.items():
        print(f"{name:32} {median:9.3f} {least:7.3f}")
    for name in ("galton-client status", "galton-client status (terminal)"):
        ratio = found[name][0] / found["galton-client --version"][0]
        print(f"{name[len('galton-client '):]} / --version (medians): {ratio:.1f} x "
              "(issue 47 asks at most 4 x)")
    if args.json:
        with open(args.json, "w", encoding="utf-8") as out:
            json.dump({k: {"median_s": v[0], "min_s": v[1]} for k, v in found.items()}, out,
                      indent=2)


if __name__ == "__main__":
    main()
