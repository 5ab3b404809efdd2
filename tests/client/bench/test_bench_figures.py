"""The recorded Galton figures (docs/data/bench-defaults) come out of the engine again, bit
for bit: a change to MuJoCo's stepping (its sleeping, say) must not move them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from support.daemons import start_daemon

from galton.analysis.board import BoardSpec
from galton.client import Client, EmbeddedDaemon
from galton.client.bench.experiment import ExperimentConfig
from galton.client.bench.trial import run_trial

BENCH_DEFAULTS = Path(__file__).resolve().parents[3] / "docs" / "data" / "bench-defaults"


@pytest.mark.slow
@pytest.mark.parametrize("release", ["stream", "all-at-once"])
def test_the_recorded_mujoco_trial_comes_out_again(daemons: dict[str, EmbeddedDaemon],
                                                    release: str) -> None:
    stored = json.loads((BENCH_DEFAULTS / release / "results.json").read_text())
    want = next(t for t in stored["trials"]
                if (t["engine"], t["balls"], t["repetition"]) == ("mujoco", 100, 0))
    config = ExperimentConfig(BoardSpec.load("paper"), engines=("mujoco",), balls=(100,),
                              repetitions=1, release=release, seed=want["seed"])
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=60.0) as sim:
        sim.load_world("mujoco")
        record = run_trial(sim, config.trials()[0])
    assert (record.counts, record.sim_time) == (want["counts"], want["sim_time"])
