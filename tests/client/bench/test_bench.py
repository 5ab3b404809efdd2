"""The Galton benchmark end to end on the small board, through real daemons."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from galton.analysis.board import BoardSpec
from galton.analysis.records import ExperimentResults
from galton.client import Client, EmbeddedDaemon
from galton.client.bench.build import ball_group, board_groups
from galton.client.bench.trial import (
    MIN_CHUNK_S,
    PROBE_S,
    SEGMENT_WALL_S,
    SETTLE_SEGMENT_S,
    WALL_CHUNK_S,
    TrialConfig,
    run_trial,
    settling_segment,
    settling_wait,
    wall_chunk,
)
from galton.client.cli.app import app
from galton.protocol import InvalidArgumentError

runner = CliRunner()
EXPECTED_FILES = ("results.json", "results.csv", "report.md", "rtf_vs_balls.png",
                  "resources_vs_balls.png")


def test_a_small_trial_settles_every_ball_and_counts_them(sim: Client, engine: str) -> None:
    board = BoardSpec.load("small")
    record = run_trial(sim, TrialConfig(engine, board, repetition=0, seed=1))
    assert record.engine == engine and record.balls == board.ball.count
    assert len(record.counts) == board.bins
    assert record.settled + record.lost + record.unsettled == record.balls
    assert record.lost == 0 and record.unsettled == 0
    assert record.rtf is not None and record.rtf > 0 and record.sim_time > 1.0
    assert record.peak_rss_bytes and record.peak_rss_bytes > 10 * 2**20
    assert record.settings["timestep"] > 0
    assert sim.list(tag="ball") and len(sim.list(tag="board")) > 20


def test_a_lone_ball_bouncing_on_the_top_pin_is_not_taken_for_stuck(sim: Client,
                                                                     engine: str) -> None:
    """One ball released over the paper board's funnel bounces on the top pin's apex; a
    rest check can catch it at the top of a bounce, slower than the settle speed."""
    board = BoardSpec.load("paper")
    board = board.replace(ball=dataclasses.replace(board.ball, count=1))
    for repetition in range(3):
        record = run_trial(sim, TrialConfig(engine, board, repetition=repetition, seed=0))
        assert (record.settled, record.unsettled, record.lost) == (1, 0, 0)


def test_trials_are_reproducible(sim: Client, engine: str) -> None:
    board = BoardSpec.load("small")
    first, second = (run_trial(sim, TrialConfig(engine, board, repetition=3, seed=7))
                     for _ in range(2))
    assert first.counts == second.counts and first.sim_time == second.sim_time


def test_bench_cli_writes_every_output(daemons: dict[str, EmbeddedDaemon],
                                       tmp_path: Path) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    out = tmp_path / "run"
    result = runner.invoke(app, [
        "bench", "--connect", daemon.endpoint, "--instances", daemon.instance,
        "--board", "small", "--balls", "10,20", "--repetitions", "2", "--out", str(out),
        "--json"])
    assert result.exit_code == 0, result.output
    summary = json.loads(result.output)
    assert {e["engine"] for e in summary["engines"]} == {"mujoco", "pybullet"}
    for name in (*EXPECTED_FILES, "histogram_mujoco.png", "histogram_pybullet.png"):
        assert (out / name).stat().st_size > 0, name
    results = ExperimentResults.from_json(out / "results.json")
    assert len(results.trials) == 8
    trial = results.trials[0].to_dict()
    assert {"engine", "balls", "counts", "settled", "lost", "chi2", "rtf", "config"} <= set(trial)
    assert "Webots" in (out / "report.md").read_text()

    rerendered = tmp_path / "again"
    again = runner.invoke(app, ["report", str(out / "results.json"), "--out", str(rerendered)])
    assert again.exit_code == 0, again.output
    assert (rerendered / "report.md").read_text() == (out / "report.md").read_text()


def test_settling_requests_are_sized_by_the_rtf_so_far() -> None:
    """A slow engine's settling request stays near SEGMENT_WALL_S of wall time (DART at
    1,000 balls once asked for 10 s of sim time at RTF ~0.01: past the 600 s wait)."""
    assert settling_segment(0.0, 0.0, 0.5) == 1.0  # a probe before any figure
    assert settling_segment(1.0, 50.0, 0.5) == SETTLE_SEGMENT_S  # fast: the cap
    slow = settling_segment(100.0, 1.0, 0.5)  # RTF 0.01
    assert slow == 0.5 and slow / 0.01 <= 2 * SEGMENT_WALL_S  # one check interval
    middling = settling_segment(10.0, 1.0, 0.5)  # RTF 0.1: 6 s of sim in about 60 s
    assert middling == pytest.approx(0.1 * SEGMENT_WALL_S)
    assert (middling / 0.5).is_integer()  # whole check intervals: the same rest checks
    assert settling_wait(0.5, 100.0, 0.1) == pytest.approx(10 * 0.5 / 0.001)  # 10 x predicted
    assert settling_wait(6.0, 10.0, 1.0) == 600.0  # never under the usual wait
    assert settling_wait(1.0, 0.0, 0.0) >= 3600.0  # the first request: no figure yet


def test_an_rtf_only_trial_stops_at_its_wall_budget_unsettled(mujoco_sim: Client) -> None:
    """The report card's curve trials: a budget spent by the first probe ends the trial
    there, every ball still in the air, with an RTF from the sim time it did run."""
    board = BoardSpec.load("small")
    record = run_trial(mujoco_sim, TrialConfig("mujoco", board, seed=1, max_wall_time=1e-6))
    assert record.sim_time == pytest.approx(PROBE_S)
    assert record.unsettled == board.ball.count and record.settled == 0
    assert record.rtf is not None and record.rtf > 0
    assert record.config["max_wall_time"] == 1e-6
    assert wall_chunk(30.0, 0.0, 0.0) == PROBE_S
    assert wall_chunk(30.0, 2.0, 1.0) == pytest.approx(0.5 * WALL_CHUNK_S)  # RTF 0.5
    assert wall_chunk(1.0, 2.0, 1.0) == pytest.approx(0.5)  # the budget left
    assert wall_chunk(1.0, 1e4, 1.0) == MIN_CHUNK_S


def test_bench_rejects_bad_options() -> None:
    result = runner.invoke(app, ["bench", "--board", "no-such-board"])
    assert result.exit_code != 0 and "no-such-board" in result.output
    result = runner.invoke(app, ["bench", "--release", "sometimes"])
    assert result.exit_code != 0 and "all-at-once" in result.output


def test_experiment_config_validates() -> None:
    from galton.client.bench.experiment import ExperimentConfig

    with pytest.raises(InvalidArgumentError):
        ExperimentConfig(board=BoardSpec.load("small"), balls=(0,))


def test_bench_never_replaces_the_world_of_a_daemon_it_was_not_pointed_at(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A user's daemon answering on the default endpoint keeps its scene: with no --connect,
    --instances or --use-running the bench starts daemons of its own."""
    import galton.client.transport.session as session_module
    from galton.client import plane, spheres

    with EmbeddedDaemon("mujoco", instance="users-robot") as daemon, \
            Client(daemon.instance, daemon.endpoint) as user:
        user.spawn(plane("ground"), spheres(["ball"], radius=0.1, positions=[[0, 0, 1]]))
        user.step(10)
        before = (user.list(), user.status().step)
        monkeypatch.setattr(session_module, "DEFAULT_ENDPOINT", daemon.endpoint)
        result = runner.invoke(app, [
            "bench", "--engines", "mujoco", "--board", "small", "--balls", "5",
            "--repetitions", "1", "--out", str(tmp_path / "run"), "--json"])
        assert result.exit_code == 0, result.output
        assert (user.list(), user.status().step) == before


def test_bench_refuses_a_misspelled_engine_before_any_trial(tmp_path: Path) -> None:
    result = runner.invoke(app, ["bench", "--engines", "mujoco,bullet", "--board", "small",
                                 "--out", str(tmp_path / "run")])
    from support.cli import flat

    assert result.exit_code == 2
    assert "'bullet'" in flat(result.output) and "did you mean 'pybullet'" in flat(result.output)
    assert not (tmp_path / "run").exists()


def test_a_failed_bench_keeps_the_trials_it_finished(daemons: dict[str, EmbeddedDaemon],
                                                     tmp_path: Path) -> None:
    """The second engine's daemon is not there: the first engine's trials stay on disk."""
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    out = tmp_path / "run"
    result = runner.invoke(app, [
        "bench", "--connect", daemon.endpoint, "--instances", f"{daemon.instance},nobody",
        "--engines", "mujoco,pybullet", "--board", "small", "--balls", "5",
        "--repetitions", "2", "--out", str(out)])
    assert result.exit_code == 1, result.output
    kept = ExperimentResults.from_json(out / "results.json")
    assert [(t.engine, t.balls) for t in kept.trials] == [("mujoco", 5), ("mujoco", 5)]
    assert kept.executor == {"kind": "local"}
    assert "2 trial(s) finished before the failure are kept" in result.output


@pytest.mark.parametrize("engine", ["mujoco", "pybullet", "ode", "dart"])
def test_the_board_brings_its_materials_to_every_body(engine: str) -> None:
    board = BoardSpec.load("paper")
    own = board.contacts[engine].bodies
    groups = [*board_groups(board, engine), ball_group(board, engine, ["b"], np.zeros((1, 3)))]
    for group in groups:
        role = group.tags[-1]
        assert (group.friction, group.restitution) == (own[role].friction,
                                                      own[role].restitution), role
    bare = board.replace(materials="engine")
    assert bare.engine_contacts(engine).params == {}
    for group in [*board_groups(bare, engine), ball_group(bare, engine, ["b"], np.zeros((1, 3)))]:
        assert group.friction is None and group.restitution is None


def test_bench_with_engine_materials_says_so(daemons: dict[str, EmbeddedDaemon],
                                             tmp_path: Path) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    result = runner.invoke(app, [
        "bench", "--connect", daemon.endpoint, "--instances", daemon.instance, "--engines",
        "mujoco", "--board", "small", "--materials", "engine", "--balls", "5",
        "--repetitions", "1", "--out", str(tmp_path), "--json"])
    assert result.exit_code == 0, result.output
    trial = ExperimentResults.from_json(tmp_path / "results.json").trials[0]
    assert trial.config["board"]["materials"] == "engine"
    assert trial.settings["mujoco.solimp"] == [0.9, 0.95, 0.001, 0.5, 2.0]
    assert "Materials: the engine's own defaults" in (tmp_path / "report.md").read_text()
    bad = runner.invoke(app, ["bench", "--board", "small", "--materials", "wood"])
    assert bad.exit_code == 2 and "--materials must be one of board, engine" in bad.output


def test_a_trial_loads_the_board_settings(mujoco_sim: Client) -> None:
    board = BoardSpec.load("small")
    board = board.replace(ball=dataclasses.replace(board.ball, count=3))
    record = run_trial(mujoco_sim, TrialConfig("mujoco", board))
    assert record.config["board"]["materials"] == "board"
    assert record.settings["mujoco.solimp"] == [0.8, 0.95, 0.001, 0.5, 2.0]
