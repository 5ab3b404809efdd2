"""Measurements the daemon publishes about itself: real-time factor, CPU and memory."""

from __future__ import annotations

import os
import resource
import time
from collections import deque
from pathlib import Path

import psutil


class ProcessMonitor:
    """CPU % (of one core) since the previous sample, current and peak RSS of this process.

    Sampled at the telemetry rate on the physics thread, so it stays cheap: CPU time from
    the process clock, RSS from /proc/self/statm where there is one (psutil elsewhere).
    """

    def __init__(self) -> None:
        self._process = psutil.Process()
        self._page_size = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
        self._statm = Path("/proc/self/statm")
        self._last = (time.monotonic(), time.process_time())

    def sample(self) -> tuple[float, int, int]:
        wall, cpu_time = time.monotonic(), time.process_time()
        last_wall, last_cpu = self._last
        self._last = (wall, cpu_time)
        cpu = 100.0 * (cpu_time - last_cpu) / (wall - last_wall) if wall > last_wall else 0.0
        rss = self._rss()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: KiB
        return cpu, rss, max(peak, rss)

    def _rss(self) -> int:
        try:
            return int(self._statm.read_text().split()[1]) * self._page_size
        except OSError:
            return int(self._process.memory_info().rss)


class RtfWindow:
    """Real-time factor measured over a sliding window of (wall, sim) samples."""

    def __init__(self, window_s: float = 1.0) -> None:
        self.window_s = window_s
        self._samples: deque[tuple[float, float]] = deque()

    def clear(self) -> None:
        self._samples.clear()

    def add(self, wall: float, sim: float) -> float:
        """Record a sample and return the RTF over the window (0 before two samples)."""
        self._samples.append((wall, sim))
        while len(self._samples) > 2 and wall - self._samples[1][0] >= self.window_s:
            self._samples.popleft()
        return self.value()

    def value(self) -> float:
        if len(self._samples) < 2:
            return 0.0
        (w0, s0), (w1, s1) = self._samples[0], self._samples[-1]
        return (s1 - s0) / (w1 - w0) if w1 > w0 else 0.0


class Pacer:
    """Decides how many steps are due so that sim time tracks wall time × target RTF."""

    # Wall seconds of backlog after which the pacer gives up catching up. Under a crowd of
    # clients the physics thread can lose the CPU for 0.3-1 s at a time (20 processes
    # rendering on 2 cores); at 0.25 s those stalls were forgiven and PyBullet fell to RTF
    # 0.89-0.92, at 2 s they are caught up (0.97; docs/PERFORMANCE.md, "Perception load").
    # A request that holds the thread longer (a render near max_pixels) is still forgiven.
    MAX_LAG_S = 2.0

    def __init__(self) -> None:
        self.rtf = 1.0
        self._wall0 = 0.0
        self._sim0 = 0.0

    def anchor(self, wall: float, sim: float, rtf: float) -> None:
        self.rtf, self._wall0, self._sim0 = rtf, wall, sim

    def steps_due(self, wall: float, sim: float, dt: float) -> int:
        """Steps to run now; -1 means "as many as you like" (RTF 0: as fast as possible)."""
        if self.rtf == 0:
            return -1
        target = self._sim0 + (wall - self._wall0) * self.rtf
        behind = target - sim
        if behind > self.MAX_LAG_S * self.rtf:
            self.anchor(wall, sim, self.rtf)
            return 1
        return max(0, int(behind / dt + 1e-9))

    def seconds_until_due(self, wall: float, sim: float, dt: float) -> float:
        if self.rtf == 0:
            return 0.0
        return max(0.0, self._wall0 + (sim + dt - self._sim0) / self.rtf - wall)
