"""The benchmarks' in-process trial, shared: ``LocalSim`` lives in benchmarks/local_sim.py.

One definition serves both folders, so a probe's in-process trial stays bit-identical to
the bridge's (benchmarks/bridge_overhead.py checks that). The probes run as scripts from
research/, so this puts benchmarks/ on the path once, here, for the probes that need it.
"""

from __future__ import annotations

import sys
from pathlib import Path

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
if str(BENCHMARKS) not in sys.path:
    sys.path.append(str(BENCHMARKS))

from local_sim import LocalSim  # noqa: E402

__all__ = ["LocalSim"]
