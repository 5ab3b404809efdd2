"""The fidelity sweep: axis parsing, cell scoring and the CLI through a real daemon."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from galton.analysis.board import SCENERY_ROLES, BoardSpec
from galton.analysis.errors import AnalysisError
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.sweep import SweepAxis, sweep_cells
from galton.client import EmbeddedDaemon
from galton.client.bench.sweep import parse_axis, with_params
from galton.client.cli.app import app
from galton.protocol import InvalidArgumentError


def test_parse_axis_reads_json_values() -> None:
    assert parse_axis("default_friction=0.1,0.3") == SweepAxis("default_friction", (0.1, 0.3))
    assert parse_axis("mujoco.solref=[0.02,0.3];[0.02,0.5]").values == ((0.02, 0.3),
                                                                       (0.02, 0.5))
    with pytest.raises(InvalidArgumentError):
        parse_axis("no-values")


def test_a_default_surface_axis_reaches_the_board_bodies_it_stands_for() -> None:
    board = BoardSpec.load("paper")
    swept = with_params(board, "mujoco", {"default_restitution": 0.4,
                                          "default_static_friction": 0.2})
    bodies = swept.contacts["mujoco"].bodies
    assert swept.contacts["mujoco"].params["default_restitution"] == 0.4
    assert bodies["ball"].restitution == 0.4 and bodies["ball"].friction == 0.5
    assert all(bodies[role].friction == 0.2 and bodies[role].restitution == 0.61
               for role in SCENERY_ROLES)
    assert swept.contacts["pybullet"] == board.contacts["pybullet"]


def _trial(restitution: float, counts: list[int], lost: int = 0) -> TrialRecord:
    return TrialRecord(engine="mujoco", engine_version="x", board="small", balls=sum(counts) +
                       lost, repetition=0, seed=0, release="all-at-once", counts=counts,
                       settled=sum(counts), lost=lost,
                       lost_by_reason={"below_floor": lost, "outside_cavity": 0, "tunnelled": 0,
                                       "nan": 0},
                       settings={"default_restitution": restitution})


def test_cells_group_by_the_swept_values() -> None:
    axis = SweepAxis("default_restitution", (0.0, 0.5))
    trials = [_trial(0.0, [1, 5, 10, 10, 5, 1]), _trial(0.0, [1, 5, 10, 10, 5, 1]),
              _trial(0.5, [10, 0, 0, 0, 0, 10], lost=2)]
    cells = {c.point: c for c in sweep_cells(trials, [axis], draws=2000)}
    assert cells[(0.0,)].trials == 2 and cells[(0.0,)].p_monte_carlo > 0.5
    assert cells[(0.5,)].p_monte_carlo < 0.01
    assert cells[(0.5,)].lost_percent == pytest.approx(100 * 2 / 22)
    with pytest.raises(AnalysisError, match="no setting"):
        sweep_cells(trials, [SweepAxis("timestep", (0.001,))])


def test_sweep_cli_writes_a_map_per_engine(daemons: dict[str, EmbeddedDaemon],
                                           tmp_path: Path) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    result = CliRunner().invoke(app, [
        "sweep", "--connect", daemon.endpoint, "--instances", daemon.instance,
        "--engines", "mujoco", "--board", "small", "--balls", "10", "--repetitions", "1",
        "--param", "default_friction=0.2,0.8", "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    cells = json.loads(result.output)["cells"]
    assert [c["point"] for c in cells] == [[0.2], [0.8]]
    assert (tmp_path / "sweep_mujoco.png").stat().st_size > 0
    saved = ExperimentResults.from_json(tmp_path / "results.json")
    assert [t.settings["default_friction"] for t in saved.trials] == [0.2, 0.8]
    assert saved.extra["sweep"]["axes"][0]["name"] == "default_friction"
