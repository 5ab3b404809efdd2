"""The bench on Ray (issue 52), on a real local Ray instance shared by the module: actors
each hosting a real daemon give the plain run's bins trial for trial; an actor whose
daemon is SIGKILLed mid-trial is restarted by Ray and its trial rerun, every trial once;
the CLI refuses what --ray cannot do. The CLI's own run, with a Ray instance of its own,
is held by the slow test_ray_cli.py."""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import ray
from support.cli import invoke, run, target_of
from support.daemons import start_daemon
from support.worlds import clean, contact_scene

from galton.analysis.board import BoardSpec
from galton.analysis.records import ExperimentResults, TrialRecord
from galton.analysis.sweep import SweepAxis
from galton.client import Client, EmbeddedDaemon
from galton.client.bench.executor import Retry, TrialHooks
from galton.client.bench.experiment import ExperimentConfig, run_experiment, run_plan
from galton.client.bench.futures import LocalFutures, predict_ensemble, start_of
from galton.client.bench.ray_executor import RayExecutor, RaySettings, ray_executor
from galton.client.bench.ray_futures import RayFutures
from galton.client.bench.sweep import run_sweep
from galton.client.cli.bench import executor_lines
from galton.client.report_card.trial_runners import executor_trials
from galton.client.sdk.recording import Recording

TIMEOUT_S = 30.0
# Four logical CPUs on any machine: room for the module's two actors and two more.
RAY_CPUS = 4
HOST_KEYS = {"cpu_model", "logical_cores", "memory_bytes", "os", "hostname", "python",
             "engines"}
PLAN_ARGS = ["--engines", "mujoco", "--board", "small", "--balls", "10", "--repetitions",
             "4", "--max-sim-time", "20"]


def small_config() -> ExperimentConfig:
    """Four MuJoCo trials of 10 balls, long enough for every ball to settle."""
    return ExperimentConfig(board=BoardSpec.load("small"), engines=("mujoco",), balls=(10,),
                            repetitions=4, max_sim_time=20.0)


def bins(trials: list[TrialRecord]) -> list[tuple[list[int], float]]:
    return [(t.counts, t.sim_time) for t in trials]


@pytest.fixture(scope="module")
def executor() -> Iterator[RayExecutor]:
    """One local Ray instance for the module (this process its driver), two actors."""
    ray.init(address="local", num_cpus=RAY_CPUS, include_dashboard=False,
             log_to_driver=False)
    try:
        with ray_executor(RaySettings("local", actors=2), "mujoco", TIMEOUT_S, 4) as started:
            yield started
    finally:
        ray.shutdown()


@pytest.fixture(scope="module")
def plain(daemons: dict[str, EmbeddedDaemon]) -> ExperimentResults:
    """The same plan run plainly, trial after trial, on one daemon here."""
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=TIMEOUT_S) as sim:
        return run_experiment({"mujoco": sim}, small_config())


def test_ray_gives_the_plain_runs_bins_trial_for_trial(
        executor: RayExecutor, plain: ExperimentResults, tmp_path: Path) -> None:
    """... and the files the actors made (a picture, the recordings) come back here."""
    finished: list[str] = []
    config = replace(small_config(), recordings=tmp_path / "recordings")
    results = run_plan(executor, config, TrialHooks(
        on_trial=lambda worker, trial, record: finished.append(worker)), pictures=tmp_path)
    assert bins(results.trials) == bins(plain.trials)
    assert results.extra["pictures"] == {
        "mujoco: the board after its first trial": "board_mujoco.png"}
    assert (tmp_path / "board_mujoco.png").read_bytes().startswith(b"\x89PNG")
    assert all(Recording.load(trial.recording).times.size  # type: ignore[arg-type]
               for trial in config.trials())
    assert all(t.settled == t.balls for t in results.trials)
    assert plain.executor == {"kind": "local"}
    assert results.executor == {"kind": "ray", "address": "local", "nodes": 1, "actors": 2,
                                "cpus_per_actor": 1.0, "retried": []}
    assert set(finished) == {"ray-1", "ray-2"} == {t.daemon for t in results.trials}
    assert set(results.hosts) == {"ray-1", "ray-2"}
    assert all(set(host) == HOST_KEYS for host in results.hosts.values())


def test_an_actor_whose_daemon_is_killed_mid_trial_is_restarted_and_its_trial_rerun(
        executor: RayExecutor, plain: ExperimentResults) -> None:
    victim = executor.facts["ray-2"]
    killed = threading.Event()

    def kill_at_first_spawn(event: dict[str, Any]) -> None:
        """The board is built: ray-2's trial is under way; SIGKILL its daemon."""
        if event.get("op") == "spawn" and not killed.is_set():
            os.kill(victim.daemon_pid, signal.SIGKILL)
            killed.set()
    retries: list[Retry] = []
    with Client(victim.name, victim.endpoint) as watcher, \
            watcher.on_event(kill_at_first_spawn):
        results = run_plan(executor, small_config(), TrialHooks(on_retry=retries.append))
    assert killed.is_set()
    assert [(t.engine, t.repetition) for t in results.trials] == [
        (t.engine, t.repetition) for t in small_config().trials()]
    assert bins(results.trials) == bins(plain.trials)  # the rerun gives the same bins
    assert [(r.worker, r.trial) for r in retries] == [("ray-2", 1)]
    assert results.executor["retried"][-1] == retries[0].to_dict()
    assert executor.incarnations["ray-2"] != victim.incarnation  # a fresh actor and daemon


def test_the_report_card_and_the_sweep_spread_their_trials_over_the_actors(
        executor: RayExecutor) -> None:
    config = ExperimentConfig(board=BoardSpec.load("small"), engines=("pybullet",),
                              balls=(5,), repetitions=2, max_sim_time=5.0)
    records = executor_trials(executor)(None, "pybullet", config)  # type: ignore[arg-type]
    assert [r.repetition for r in records] == [0, 1] and all(r.balls == 5 for r in records)
    swept = run_sweep(executor, config, [SweepAxis("default_friction", (0.3, 0.6))])
    assert [t.settings["default_friction"] for t in swept.trials] == [0.3, 0.3, 0.6, 0.6]
    assert swept.executor["kind"] == "ray" and "sweep" in swept.extra


def test_ray_refuses_daemons_already_running_and_more_actors_than_cpus(
        executor: RayExecutor, tmp_path: Path) -> None:
    both = run(["bench", "--ray", "local", "--pool", *PLAN_ARGS, "--out", str(tmp_path)])
    assert both.exit_code == 2 and "leave out --pool" in both.output
    wide = run(["bench", "--ray", "local", "--ray-actors", "9", *PLAN_ARGS,
                "--out", str(tmp_path)])
    assert wide.exit_code == 1
    assert "9 Ray actor(s) of 1 CPU(s) each need 9 CPUs; the cluster at local has 4" in (
        wide.output)


def test_the_output_says_which_trials_were_retried() -> None:
    retry = Retry("ray-2", 1, "mujoco", 10, 1, "its actor died")
    said = executor_lines({"kind": "ray", "address": "auto", "nodes": 2, "actors": 4,
                           "retried": [retry.to_dict()]})
    assert said == ["Ran on Ray (auto): 4 actor(s) on 2 node(s); 1 trial(s) retried",
                    "  retried: trial 2 (mujoco 10 balls rep 2) on ray-2: its actor died"]
    assert executor_lines({"kind": "local"}) == []


ENSEMBLE = {"perturb": {"position": 0.002, "velocity": 0.02}, "seed": 11}


@pytest.fixture
def scene(daemons: dict[str, EmbeddedDaemon]) -> Iterator[tuple[Client, list[str]]]:
    """A contact scene on the session's MuJoCo daemon, a few steps in, and its bodies."""
    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint, timeout=TIMEOUT_S) as sim, clean(sim):
        sim.load_world("mujoco")  # a fresh, empty world
        names = contact_scene(sim)
        sim.step(5)
        yield sim, names


def same_prediction(found: Any, want: Any) -> None:
    assert (found.futures, found.seed, found.steps) == (want.futures, want.seed, want.steps)
    for key in ("times", "poses", "twists", "spread", "scores"):
        np.testing.assert_array_equal(getattr(found, key), getattr(want, key), err_msg=key)


def test_futures_over_two_actors_are_one_daemons_ensemble_bit_for_bit(
        executor: RayExecutor, scene: tuple[Client, list[str]]) -> None:
    """Seven futures cut into batches (4 + 3) on two actors, and on this daemon (one batch
    in a side world restored from the snapshot), against one call on the world itself: the
    same futures, spread and scores, bit for bit."""
    source, names = scene
    dt = source.status().timestep
    ask = {"read": names, "every": 10 * dt, "score": {"body": names[0],
                                                      "target": [0.0, 0.0, 0.0]}}
    want = source.predict(30 * dt, futures=7, **ENSEMBLE, **ask)
    start = start_of(source)
    runner = RayFutures(executor)
    found = predict_ensemble(runner, start, 30 * dt, 7, **ENSEMBLE, **ask)
    same_prediction(found, want)
    assert {a.name for a in ray.get([a.facts.remote() for a in executor.actors.values()])
            } == {"ray-1", "ray-2"} and runner.retried == []
    local = LocalFutures(source)
    try:
        same_prediction(predict_ensemble(local, start, 30 * dt, 7, **ENSEMBLE, **ask), want)
    finally:
        local.close()
    assert len(source.list_worlds()) == 1  # nothing left behind


def test_an_actor_killed_mid_ensemble_is_restarted_and_its_batch_rerun(
        executor: RayExecutor, scene: tuple[Client, list[str]]) -> None:
    source, names = scene
    source.step(2)  # a start the actors have not restored yet
    dt = source.status().timestep
    want = source.predict(20 * dt, futures=6, read=names, **ENSEMBLE)
    victim = ray.get(executor.actors["ray-2"].facts.remote())
    killed = threading.Event()

    def kill_at_restore(event: dict[str, Any]) -> None:
        """The actor made the snapshot's world: its batch is under way; SIGKILL its daemon."""
        if event.get("kind") == "world" and not killed.is_set():
            os.kill(victim.daemon_pid, signal.SIGKILL)
            killed.set()
    runner = RayFutures(executor)
    with Client(victim.name, victim.endpoint) as watcher, watcher.on_event(kill_at_restore):
        found = predict_ensemble(runner, start_of(source), 20 * dt, 6, read=names,
                                 **ENSEMBLE)
    assert killed.is_set()
    same_prediction(found, want)
    assert [(r.worker, r.first_future, r.futures) for r in runner.retried] == [
        ("ray-2", 3, 3)]
    assert executor.incarnations["ray-2"] != victim.incarnation


def test_the_cli_spreads_a_slots_futures_over_actors_of_its_own(
        executor: RayExecutor, scene: tuple[Client, list[str]],
        daemons: dict[str, EmbeddedDaemon]) -> None:
    """``predict --futures 5 --ray local --slot S`` (on this process's Ray instance, two
    actors of its own, stopped after) gives the one-daemon ensemble of the slot."""
    source, names = scene
    source.snapshot(slot="before")
    source.step(3)  # the slot is not the present
    target = target_of(start_daemon(daemons, "mujoco"))
    ask = ["predict", "0.02", "--every", "0.01", "--read", ",".join(names[:2]),
           "--futures", "5", "--perturb", "position=0.001", "--seed", "3",
           "--slot", "before"]
    want = invoke([*target, *ask, "--json"])
    found = invoke([*target, *ask, "--ray", "local", "--ray-actors", "2", "--json"])
    assert found.pop("executor") == {"kind": "ray", "address": "local", "nodes": 1,
                                     "actors": 2, "cpus_per_actor": 1.0, "retried": []}
    assert found == want and found["futures"] == 5
    assert len(source.list_worlds()) == 1  # the slot's side world was deleted
