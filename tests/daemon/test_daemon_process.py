"""The daemon as a process: discovery, telemetry, events, raw clients, clean shutdown."""

from __future__ import annotations

import contextlib
import importlib.util
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
import zenoh

from galton.client import Client, EmbeddedDaemon, instances, plane, spheres, wait_for_daemon
from galton.daemon.server import SHUTDOWN_GRACE_S
from galton.protocol import DaemonUnreachableError, GaltonError, OperationFailedError, Telemetry

ROOT = Path(__file__).resolve().parents[2]


def load_example(name: str):  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location(name, ROOT / "examples" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(module)
    return module


def test_sigterm_withdraws_liveliness_and_exits_zero() -> None:
    daemon = EmbeddedDaemon("mujoco", instance="short-lived").start()
    gone = threading.Event()
    with Client(daemon.instance, daemon.endpoint) as watcher:
        wait_for_daemon(watcher.session, daemon.instance, 30)
        sub = watcher.session.liveliness().declare_subscriber(
            watcher.keys.alive, lambda s: gone.set() if s.kind == zenoh.SampleKind.DELETE else None)
        daemon.process.send_signal(signal.SIGTERM)
        assert daemon.stop() == 0
        sub.undeclare()
    assert gone.wait(10)


def test_a_pybullet_daemon_prints_only_its_own_lines() -> None:
    """PyBullet's build banner and its "argv[0]=" line stay out of the daemon's output;
    the readiness line is there (issue 33)."""
    daemon = EmbeddedDaemon("pybullet", instance="quiet").start()
    with Client(daemon.instance, daemon.endpoint) as client:
        client.load_world("pybullet")  # a second PyBullet connection
    daemon.process.send_signal(signal.SIGTERM)
    assert daemon.stop() == 0
    assert "galton-daemon ready" in daemon.output
    assert "build time" not in daemon.output and "argv[0]" not in daemon.output


def test_sigint_also_exits_zero() -> None:
    daemon = EmbeddedDaemon("mujoco", instance="interrupted").start()
    daemon.process.send_signal(signal.SIGINT)
    assert daemon.stop() == 0


def test_a_step_job_in_flight_at_sigterm_is_answered_and_the_daemon_exits_zero() -> None:
    """The physics loop runs on the daemon's main thread; a signal must still stop it
    between chunks and answer the request it was serving."""
    daemon = EmbeddedDaemon("mujoco", instance="busy-at-exit").start()
    outcome: list[Exception | None] = []
    with Client(daemon.instance, daemon.endpoint) as sim, \
            Client(daemon.instance, session=sim.session) as probe:
        sim.spawn(plane(), spheres(["b"], [[0.0, 0.0, 0.5]], 0.05))

        def long_run() -> None:
            try:
                sim.run_until(1e6, timeout=60)
                outcome.append(None)
            except Exception as error:
                outcome.append(error)
        stepping = threading.Event()
        with probe.on_telemetry(lambda t: stepping.set() if t.step > 0 else None):
            runner = threading.Thread(target=long_run)
            runner.start()
            assert stepping.wait(30), "the long run never started"
        daemon.process.send_signal(signal.SIGTERM)
        runner.join(30)
        assert daemon.stop() == 0
    assert len(outcome) == 1
    assert isinstance(outcome[0], OperationFailedError)
    assert "shutting down" in str(outcome[0])


def test_unreachable_daemon_is_its_own_error() -> None:
    with pytest.raises(DaemonUnreachableError, match="no Zenoh peer"):
        Client("nobody", "tcp/127.0.0.1:1")


def test_wrong_instance_is_unreachable_not_empty(mujoco_sim: Client) -> None:
    with Client("no-such-instance", session=mujoco_sim.session) as other, \
            pytest.raises(DaemonUnreachableError, match="no daemon serves"):
        other.status()


def test_liveliness_discovery_lists_the_daemon(mujoco_sim: Client) -> None:
    assert mujoco_sim.instance in instances(mujoco_sim.session)


def test_telemetry_carries_clock_and_footprint(mujoco_sim: Client) -> None:
    with mujoco_sim.telemetry(timeout=5) as stream:
        samples = [next(stream) for _ in range(3)]
    assert [s.seq for s in samples] == sorted(s.seq for s in samples)
    last = samples[-1]
    assert last.engine == "mujoco" and last.rss_bytes > 10 * 2**20
    assert last.peak_rss_bytes >= last.rss_bytes and last.cpu_percent >= 0
    assert last.timestep > 0 and last.state == "stopped"


def test_telemetry_callback_and_events(mujoco_sim: Client) -> None:
    got_sample = threading.Event()
    got_state = threading.Event()
    samples: list[Telemetry] = []

    def on_sample(sample: Telemetry) -> None:
        samples.append(sample)
        got_sample.set()

    with mujoco_sim.on_telemetry(on_sample), mujoco_sim.on_event(
            lambda e: got_state.set() if e.get("kind") == "state" else None):
        assert got_sample.wait(5)
        mujoco_sim.step(1)
        assert got_state.wait(5)
    assert samples[0].instance == mujoco_sim.instance


def test_a_raw_zenoh_msgpack_client_works(daemons: dict) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    with Client(daemon.instance, daemon.endpoint) as sim:
        sim.load_world("mujoco")
        sim.spawn(spheres(["mine"], [[0.0, 0.0, 3.0]], radius=0.1))
        before = sim.list()
        heights = load_example("raw_protocol_client").main(daemon.endpoint, daemon.instance)
        # In a world of its own, on its ground: the live world is as it was, no side world left.
        assert [e.name for e in sim.list()] == [e.name for e in before] == ["mine"]
        assert [w.name for w in sim.list_worlds()] == ["default"]
    assert len(heights) == 100 and max(heights) < 2.0 and min(heights) > 0.05


def test_the_quickstart_example_runs(daemons: dict) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    load_example("quickstart").main([daemon.endpoint, daemon.instance])


def test_a_daemon_without_telemetry_still_serves() -> None:
    """--telemetry-rate 0 means no telemetry, not a physics thread waiting for ever on it."""
    with EmbeddedDaemon("mujoco", instance="quiet", telemetry_rate=0.0) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=10.0) as client:
        wait_for_daemon(client.session, daemon.instance, 30)
        samples: list[Telemetry] = []
        with client.on_telemetry(samples.append):
            client.load_world("mujoco")
            assert client.step(25).step == 25
            client.pause()
            assert client.status().state == "paused"
            assert client.step(5).step == 30
        assert samples == []


def test_sigterm_in_the_middle_of_a_long_spawn_ends_the_daemon() -> None:
    """A 100,000-body spawn holds the GIL inside the engine for seconds: SIGTERM must not
    wait for it (issue 22). The process ends by the signal's default action."""
    daemon = EmbeddedDaemon("pybullet", instance="long-spawn").start()
    assert daemon.process is not None
    process = psutil.Process(daemon.process.pid)
    names = [f"s{i}" for i in range(100_000)]
    grid = np.column_stack([np.arange(100_000) % 300 * 0.1, np.arange(100_000) // 300 * 0.1,
                            np.zeros(100_000)])
    with Client(daemon.instance, daemon.endpoint, timeout=120) as client:
        cpu = sum(process.cpu_times()[:2])

        def spawn() -> None:
            with contextlib.suppress(GaltonError):  # no reply: the daemon is gone
                client.spawn(spheres(names, grid, 0.04, static=True), timeout=120)
        request = threading.Thread(target=spawn, daemon=True)
        request.start()
        deadline = time.monotonic() + 60
        while sum(process.cpu_times()[:2]) - cpu < 0.3:  # the spawn is being worked on
            assert request.is_alive() and time.monotonic() < deadline, \
                "the spawn never got under way"
            request.join(0.01)
        daemon.process.send_signal(signal.SIGTERM)
        code = daemon.process.wait(10)
        daemon.stop()
        request.join(30)  # its request ends with the daemon: before the client closes
        assert not request.is_alive()
    assert code == -signal.SIGTERM  # ended inside the spawn: not after it, gracefully


def test_sigterm_while_a_long_spawn_is_decoded_refuses_it_and_exits_within_the_grace() -> None:
    """SIGTERM that lands while a 100,000-body spawn is still being decoded (before its work
    began) used to let the spawn begin: PyBullet's one createMultiBody call held the GIL
    past the grace, and the exit took 5.8 s (issue 35). Now the spawn is refused ("shutting
    down") and the daemon exits gracefully, well within the grace; or, had the work begun
    before the signal, the signal ends it at once (or the request never reached it)."""
    daemon = EmbeddedDaemon("pybullet", instance="decoded-spawn").start()
    assert daemon.process is not None
    process = psutil.Process(daemon.process.pid)
    count = 100_000
    grid = np.column_stack([np.arange(count) % 300 * 0.1, np.arange(count) // 300 * 0.1,
                            np.zeros(count)])
    group = spheres([f"s{i}" for i in range(count)], grid, 0.04, static=True)
    replies: list[GaltonError] = []
    with Client(daemon.instance, daemon.endpoint, timeout=120) as client:
        cpu = sum(process.cpu_times()[:2])

        def spawn() -> None:
            try:
                client.spawn(group, timeout=120)
            except GaltonError as error:
                replies.append(error)
        request = threading.Thread(target=spawn, daemon=True)
        request.start()
        deadline = time.monotonic() + 60
        while sum(process.cpu_times()[:2]) - cpu < 0.05:  # the payload is being decoded
            assert request.is_alive() and time.monotonic() < deadline
            request.join(0.002)
        sent = time.monotonic()
        daemon.process.send_signal(signal.SIGTERM)
        code = daemon.process.wait(30)
        took = time.monotonic() - sent
        daemon.stop()
        request.join(30)
    assert took < SHUTDOWN_GRACE_S, f"exit took {took:.2f} s"  # the old path: 1.7-5.8 s
    assert code in (0, -signal.SIGTERM)
    if code == 0 and replies and not isinstance(replies[0], DaemonUnreachableError):
        # refused, not begun (unreachable: the request never got to the daemon)
        assert isinstance(replies[0], OperationFailedError), replies
        assert "shutting down" in str(replies[0])


def test_help_into_a_pipe_is_whole() -> None:
    """Issue 47: ``galton-daemon --help | less`` was cut at 80 columns, its options' help
    ending in "…"; "[ros2]" is kept (rich once read it as markup)."""
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "TERMINAL_WIDTH")}
    done = subprocess.run([str(Path(sys.executable).with_name("galton-daemon")), "--help"],
                          capture_output=True, text=True, env=env, timeout=60, check=True)
    assert "…" not in done.stdout and "needs the [ros2] extra" in done.stdout, done.stdout
