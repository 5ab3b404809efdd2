"""Shared bits of the benchmark scripts: daemons on free ports, timing, tables."""

from __future__ import annotations

import json
import platform
import statistics
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import psutil

from galton.client import Client, EmbeddedDaemon, wait_for_daemon

ENGINES = ("mujoco", "pybullet")


@contextmanager
def daemon_client(engine: str, telemetry_rate: float = 10.0, timeout: float = 60.0,
                  zmq: bool = False, extra_args: list[str] | None = None
                  ) -> Iterator[tuple[EmbeddedDaemon, Client]]:
    """A fresh daemon of that engine on a free loopback port (and a ZeroMQ ipc socket with
    ``zmq``), and a Zenoh client to it."""
    with EmbeddedDaemon(engine, instance=f"bench-{engine}", telemetry_rate=telemetry_rate,
                        zmq=zmq, extra_args=extra_args) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=timeout) as client:
        wait_for_daemon(client.session, daemon.instance, 30)
        yield daemon, client


def rss_mb(daemon: EmbeddedDaemon) -> float:
    assert daemon.process is not None
    return psutil.Process(daemon.process.pid).memory_info().rss / 1e6


def timed(action: Callable[[], object], repeat: int) -> list[float]:
    """Wall seconds of each of ``repeat`` calls."""
    samples = []
    for _ in range(repeat):
        started = time.perf_counter()
        action()
        samples.append(time.perf_counter() - started)
    return samples


def percentiles_ms(samples: list[float]) -> dict[str, float]:
    data = np.asarray(samples) * 1e3
    return {"p50": float(np.percentile(data, 50)), "p99": float(np.percentile(data, 99)),
            "mean": float(statistics.fmean(data)), "n": len(samples)}


def p50_p99(p: Mapping[str, float], digits: int = 2) -> str:
    """A ``percentiles_ms`` result as the tables' "p50 / p99" cell."""
    return f"{p['p50']:.{digits}f} / {p['p99']:.{digits}f}"


def machine() -> str:
    return f"{platform.node()} {platform.machine()} {psutil.cpu_count()} CPUs"


def write_json(path: str | None, data: object) -> None:
    if path:
        Path(path).write_text(json.dumps(data, indent=2))
