"""What machine a daemon runs on, for results that compare computers (issue 27).

A benchmark spread over several hosts records which one ran each trial; the paper compared
two computers, so a figure means little without the CPU, cores, memory and versions beside
it. Computed once per process: none of it changes while the daemon runs.
"""

from __future__ import annotations

import ctypes.util
import functools
import importlib.metadata
import os
import platform
from pathlib import Path
from typing import Any

import psutil

ENGINE_PACKAGES = ("mujoco", "pybullet", "dartpy")
CPUINFO = Path("/proc/cpuinfo")


@functools.cache
def host_info() -> dict[str, Any]:
    """This host as a plain map (the ``host`` field of ``capabilities``)."""
    return {
        "cpu_model": cpu_model(),
        "logical_cores": os.cpu_count() or 0,
        "memory_bytes": int(psutil.virtual_memory().total),
        "os": platform.platform(),
        "hostname": platform.node(),
        "python": platform.python_version(),
        "engines": engine_versions(),
    }


def cpu_model(cpuinfo: Path = CPUINFO) -> str:
    """The CPU's marketing name: Linux's "model name", else what ``platform`` knows."""
    try:
        for line in cpuinfo.read_text(encoding="utf-8", errors="replace").splitlines():
            key, _, value = line.partition(":")
            if key.strip() == "model name" and value.strip():
                return value.strip()
    except OSError:
        pass
    return platform.processor() or platform.machine() or "unknown"


def engine_versions() -> dict[str, str]:
    """Installed engine versions by package name ("not installed" where absent)."""
    found = {}
    for package in ENGINE_PACKAGES:
        try:
            found[package] = importlib.metadata.version(package)
        except importlib.metadata.PackageNotFoundError:
            found[package] = "not installed"
    found["ode"] = ctypes.util.find_library("ode") or "not installed"  # a system library
    return found
