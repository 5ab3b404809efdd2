"""Records of a pooled run: which daemon ran each trial, and the hosts behind them."""

from __future__ import annotations

import json
from pathlib import Path

from galton.analysis.records import ExperimentResults, TrialRecord

HOST = {"cpu_model": "Test CPU", "logical_cores": 2, "memory_bytes": 2**32, "os": "Linux",
        "hostname": "a", "python": "3.11", "engines": {"mujoco": "3.3"}}


def trial(daemon: str = "") -> TrialRecord:
    return TrialRecord(engine="mujoco", engine_version="3.3", board="small", balls=3,
                       repetition=0, seed=0, release="all-at-once", counts=[1, 2, 0],
                       settled=3, daemon=daemon)


def test_the_daemon_and_hosts_survive_a_round_trip(tmp_path: Path) -> None:
    results = ExperimentResults(trials=[trial("pool-a"), trial("pool-b")],
                                hosts={"pool-a": HOST, "pool-b": HOST})
    path = results.to_json(tmp_path / "results.json")
    assert ExperimentResults.from_json(path) == results
    data = json.loads(path.read_text())
    assert [t["daemon"] for t in data["trials"]] == ["pool-a", "pool-b"]
    assert data["hosts"]["pool-a"]["cpu_model"] == "Test CPU"


def test_results_written_before_pools_still_read(tmp_path: Path) -> None:
    data = ExperimentResults(trials=[trial()]).to_dict()
    del data["hosts"]
    del data["trials"][0]["daemon"]
    path = tmp_path / "old.json"
    path.write_text(json.dumps(data))
    old = ExperimentResults.from_json(path)
    assert old.hosts == {} and old.trials[0].daemon == ""
