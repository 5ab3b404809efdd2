"""What a benchmark runs when the command line does not say: plain values, importable
without the bench's engines, numpy or plots (the CLI shows them in its help)."""

from __future__ import annotations

import os

DEFAULT_ENGINES = ("mujoco", "pybullet")
DEFAULT_BALLS = (100,)
DEFAULT_REPETITIONS = 10
DEFAULT_MAX_SIM_TIME_S = 120.0
MAX_DEFAULT_POOL = 4


def default_pool_size() -> int:
    """Embedded daemons for ``--pool`` with nothing running: one per core, at most 4."""
    return max(1, min(os.cpu_count() or 1, MAX_DEFAULT_POOL))
