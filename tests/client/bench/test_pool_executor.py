"""Many daemons as one pool (issue 27), on loopback: a router and three daemons on their own
ports that connect to the router only; a client that knows the router alone finds them all,
spreads a bench over them, and loses no trial when one is killed mid-trial."""

from __future__ import annotations

import json
import subprocess
import threading
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from support.cli import CONSOLE_COMMAND, NOWHERE, flat, invoke, run
from support.router import RouterProcess

from galton.analysis.board import BoardSpec
from galton.analysis.records import ExperimentResults
from galton.client import Client, EmbeddedDaemon, wait_for_daemon
from galton.client.bench.daemons import pool_clients
from galton.client.bench.experiment import ExperimentConfig
from galton.client.bench.pool_executor import PoolHooks, TrialQueue, run_pool
from galton.client.bench.trial import run_trial
from galton.client.cli.router import DEFAULT_ROUTER_LISTEN, router_config
from galton.client.transport.discovery import discover_at
from galton.client.transport.session import close_session, open_session
from galton.protocol import DaemonUnreachableError

START_TIMEOUT_S = 60.0
TIMEOUT_S = 30.0
HOST_KEYS = {"cpu_model", "logical_cores", "memory_bytes", "os", "hostname", "python",
             "engines"}
# A small plan: both engines (any daemon serves any engine), 10 balls, 3 repetitions.
PLAN_ARGS = ["--engines", "mujoco,pybullet", "--board", "small", "--balls", "10",
             "--repetitions", "3", "--max-sim-time", "4"]


def small_config() -> ExperimentConfig:
    return ExperimentConfig(board=BoardSpec.load("small"), engines=("mujoco", "pybullet"),
                            balls=(10,), repetitions=3, max_sim_time=4.0)


def joined(router: RouterProcess, instance: str) -> EmbeddedDaemon:
    """A daemon on its own port that connects to the router only."""
    daemon = EmbeddedDaemon("mujoco", instance=instance, telemetry_rate=20.0,
                            extra_args=["--connect", router.endpoint])
    daemon.start(START_TIMEOUT_S)
    with Client(instance, router.endpoint) as probe:
        wait_for_daemon(probe.session, instance, START_TIMEOUT_S)
    return daemon


@pytest.fixture(scope="module")
def router() -> Iterator[RouterProcess]:
    with RouterProcess() as started:
        yield started
    assert started.returncode == 0, "".join(started.output)


@pytest.fixture(scope="module")
def three(router: RouterProcess) -> Iterator[list[EmbeddedDaemon]]:
    daemons: list[EmbeddedDaemon] = []
    try:
        for i in range(3):
            daemons.append(joined(router, f"pool-test-{i}"))
        yield daemons
    finally:
        for daemon in daemons:
            daemon.stop()


def test_a_client_of_the_router_finds_all_three_with_their_hosts(
        router: RouterProcess, three: list[EmbeddedDaemon]) -> None:
    found = {d.instance: d for d in discover_at(router.endpoint, TIMEOUT_S)}
    assert {d.instance for d in three} <= set(found)
    for daemon in three:
        info = found[daemon.instance]
        assert info.reachable and set(info.host) == HOST_KEYS and info.zmq == []
    listed = invoke(["--connect", router.endpoint, "daemons", "--json"])
    assert all(set(d["host"]) == HOST_KEYS for d in listed)
    human = flat(run(["--connect", router.endpoint, "daemons"]).output)
    assert f"{found[three[0].instance].host['logical_cores']} cores" in human


def test_bench_pool_spreads_the_plan_over_all_three(
        router: RouterProcess, three: list[EmbeddedDaemon], tmp_path: Path) -> None:
    names = [d.instance for d in three]
    out = tmp_path / "pooled"
    invoke(["--connect", router.endpoint, "bench", "--pool", "--instances", ",".join(names),
            *PLAN_ARGS, "--out", str(out), "--json"])
    results = ExperimentResults.from_json(out / "results.json")
    plan = small_config().trials()
    assert [(t.engine, t.repetition) for t in results.trials] == [
        (t.engine, t.repetition) for t in plan]
    assert {t.daemon for t in results.trials} == set(names)
    assert set(results.hosts) == set(names)
    assert all(set(host) == HOST_KEYS for host in results.hosts.values())
    assert results.extra["pool"] == {"daemons": names, "failovers": []}
    assert results.executor == {"kind": "pool", "daemons": 3, "nodes": 1}
    assert json.loads((out / "results.json").read_text())["trials"][0]["daemon"] in names
    # A trial's bins do not depend on the daemon: run each engine's first elsewhere.
    for index in (0, 3):
        record = results.trials[index]
        other = names[(names.index(record.daemon) + 1) % len(names)]
        with Client(other, router.endpoint, timeout=TIMEOUT_S) as sim:
            again = run_trial(sim, plan[index])
        assert (again.counts, again.sim_time) == (record.counts, record.sim_time)


def test_a_daemon_killed_mid_trial_loses_no_trial(
        router: RouterProcess, three: list[EmbeddedDaemon]) -> None:
    victim = joined(router, "pool-test-victim")
    killed = threading.Event()

    def kill_at_first_spawn(event: dict[str, Any]) -> None:
        """The board is built: the victim's trial is under way; SIGKILL it."""
        if event.get("op") == "spawn" and not killed.is_set() and victim.process:
            victim.process.kill()
            killed.set()
    names = [three[0].instance, three[1].instance, victim.instance]
    started: list[str] = []
    try:
        with Client(victim.instance, router.endpoint) as watcher, \
                watcher.on_event(kill_at_first_spawn), \
                pool_clients(router.endpoint, names, TIMEOUT_S, 1, "mujoco") as daemons:
            results = run_pool(daemons.clients, small_config(), daemons.hosts,
                               PoolHooks(on_start=lambda name, trial: started.append(name)))
    finally:
        victim.stop()
    assert killed.is_set() and victim.instance in started
    plan = small_config().trials()
    assert [(t.engine, t.repetition) for t in results.trials] == [
        (t.engine, t.repetition) for t in plan]
    failovers = results.extra["pool"]["failovers"]
    assert [f["daemon"] for f in failovers] == [victim.instance]
    lost = failovers[0]
    assert "Unreachable" in lost["error"] or "Timeout" in lost["error"]
    assert results.trials[lost["trial"]].daemon in names[:2]
    assert all(t.settled + t.lost + t.unsettled == t.balls for t in results.trials)


def test_pool_with_no_daemon_is_a_clear_error(tmp_path: Path) -> None:
    nowhere = run([*NOWHERE, "bench", "--pool", *PLAN_ARGS, "--out", str(tmp_path)])
    assert nowhere.exit_code == 1 and "unreachable" in nowhere.output
    with RouterProcess() as empty:
        alone = run(["--connect", empty.endpoint, "bench", "--pool", *PLAN_ARGS,
                     "--out", str(tmp_path)])
    assert alone.exit_code == 1 and "no galton daemon is there to pool" in flat(alone.output)


def test_the_queue_hands_a_put_back_trial_to_a_waiting_worker() -> None:
    queue = TrialQueue(2)
    assert (queue.take(), queue.take()) == (0, 1)
    handed: list[int | None] = []
    waiter = threading.Thread(target=lambda: handed.append(queue.take()))
    waiter.start()  # nothing pending, two in flight: it waits
    queue.done()
    queue.put_back(1)
    waiter.join(TIMEOUT_S)
    assert handed == [1]
    queue.done()
    assert queue.take() is None and queue.left() == []


def test_with_nothing_running_the_pool_starts_its_own_daemons() -> None:
    try:
        close_session(open_session(None))
        pytest.skip("a daemon answers on the default endpoint: the pool would use it")
    except DaemonUnreachableError:
        pass
    config = ExperimentConfig(board=BoardSpec.load("small"), engines=("pybullet",),
                              balls=(5,), repetitions=2, max_sim_time=2.0)
    with pool_clients(None, None, TIMEOUT_S, 2, "mujoco") as daemons:
        assert sorted(daemons.clients) == ["pool-1", "pool-2"]
        assert all(set(host) == HOST_KEYS for host in daemons.hosts.values())
        results = run_pool(daemons.clients, config, daemons.hosts)
    assert len(results.trials) == 2 and {t.daemon for t in results.trials} <= {
        "pool-1", "pool-2"}


def test_a_router_on_a_port_in_use_fails_with_one_line(router: RouterProcess) -> None:
    taken = subprocess.run([CONSOLE_COMMAND, "router", "--listen", router.endpoint],
                           capture_output=True, text=True, timeout=TIMEOUT_S, check=False)
    assert taken.returncode == 1 and taken.stdout == ""
    assert taken.stderr.startswith(f"galton-client: the router could not start on "
                                   f"{router.endpoint}")


def test_a_pool_whose_only_daemon_dies_says_what_was_not_run(router: RouterProcess) -> None:
    lone = joined(router, "pool-test-lone")

    def kill_at_first_spawn(event: dict[str, Any]) -> None:
        if event.get("op") == "spawn" and lone.process:
            lone.process.kill()
    try:
        with Client(lone.instance, router.endpoint) as watcher, \
                watcher.on_event(kill_at_first_spawn), \
                pool_clients(router.endpoint, [lone.instance], TIMEOUT_S, 1, "mujoco") as \
                daemons, pytest.raises(DaemonUnreachableError) as failed:
            run_pool(daemons.clients, small_config(), daemons.hosts)
    finally:
        lone.stop()
    message = str(failed.value)
    assert message.startswith("every daemon of the pool failed (pool-test-lone: ")
    assert message.endswith("6 of 6 trials did not run")


def test_a_router_config_file_silent_on_listen_keeps_the_loopback_default(
        tmp_path: Path) -> None:
    """Zenoh's own router default listens on every interface: a --zenoh-config file that
    names no listen endpoint (TLS settings alone, say) keeps the documented loopback default;
    a file that names some is honoured, and --listen wins over both."""
    silent, listening = tmp_path / "silent.json5", tmp_path / "listening.json5"
    silent.write_text('{transport: {link: {tx: {lease: 10000}}}}')
    listening.write_text('{listen: {endpoints: ["tcp/127.0.0.1:7999"]}}')

    def listens(listen: list[str], config_file: Path) -> Any:
        return json.loads(router_config(listen, [], False, config_file).get_json(
            "listen/endpoints"))
    assert listens([], silent) == [DEFAULT_ROUTER_LISTEN]
    assert listens([], listening) == ["tcp/127.0.0.1:7999"]
    assert listens(["tcp/127.0.0.1:7998"], listening) == ["tcp/127.0.0.1:7998"]


def test_a_daemon_whose_control_another_holds_is_dropped(
        router: RouterProcess, three: list[EmbeddedDaemon]) -> None:
    """Another client holds one daemon's control: its trial is refused (CONTROL_HELD) and
    re-run on the others, none lost."""
    held, free = three[0].instance, three[1].instance
    with Client(held, router.endpoint) as holder, holder.control(), \
            pool_clients(router.endpoint, [held, free], TIMEOUT_S, 1, "mujoco") as daemons:
        results = run_pool(daemons.clients, small_config(), daemons.hosts)
    plan = small_config().trials()
    assert [(t.engine, t.repetition) for t in results.trials] == [
        (t.engine, t.repetition) for t in plan]
    assert {t.daemon for t in results.trials} == {free}
    failovers = results.extra["pool"]["failovers"]
    assert [f["daemon"] for f in failovers] == [held]
    assert "ControlHeld" in failovers[0]["error"] or "CONTROL_HELD" in failovers[0]["error"]
