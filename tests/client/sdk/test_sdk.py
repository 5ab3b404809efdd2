"""The SDK's edges against real daemons: stamps taken from each request's own reply,
unreachable versus busy decided by the daemon's liveliness token, checked timeouts with the
operation registry's defaults, a closed Client, and what ``galton.client`` exports."""

from __future__ import annotations

import inspect
import json
import math
import queue
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numpy as np
import pytest
from support import ground_and_balls

import galton.client
from galton.client import (
    Client,
    ClientClosedError,
    DaemonUnreachableError,
    EmbeddedDaemon,
    InvalidArgumentError,
    RequestTimeoutError,
    Stamp,
    States,
    camera,
    instances,
    plane,
    spheres,
    wait_for_daemon,
)
from galton.protocol import errors
from galton.protocol.operations import LONG_RUNNING_TIMEOUT_S, OPERATIONS

BAD_TIMEOUTS = [0, 0.0, -1.0, math.nan, math.inf, -math.inf, True, "5"]
EVENT_WAIT_S = 20.0


# -- exports ------------------------------------------------------------------------------
def test_every_error_class_is_exported_from_galton_client() -> None:
    error_classes = {name for name, value in vars(errors).items()
                     if inspect.isclass(value) and issubclass(value, errors.GaltonError)}
    assert "ClientClosedError" in error_classes
    assert error_classes <= set(galton.client.__all__)
    for name in error_classes:
        assert getattr(galton.client, name) is getattr(errors, name)


def test_value_types_are_exported_from_galton_client() -> None:
    wanted = {"SimStatus", "SimState", "Telemetry", "Capabilities", "EntityInfo", "BodyGroup",
              "BodyProperties", "Stamp", "States", "Reply", "ResultCode", "DaemonInfo"}
    assert wanted <= set(galton.client.__all__)
    assert all(hasattr(galton.client, name) for name in galton.client.__all__)


def test_dir_lists_every_export_before_its_first_use() -> None:
    """dir() and tab completion see the lazy exports too (issue 47: only loaded ones),
    and listing them loads nothing."""
    probe = ("import sys, json, galton.client, galton.protocol\n"
             "print(json.dumps([dir(galton.client), dir(galton.protocol), "
             "'numpy' in sys.modules]))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=60, check=True)
    client_names, protocol_names, numpy_loaded = json.loads(done.stdout)
    assert set(galton.client.__all__) <= set(client_names)
    assert {"Client", "spheres", "EmbeddedDaemon", "SimStatus"} <= set(client_names)
    assert {"Keys", "SimStatus", "ENGINE_NAMES"} <= set(protocol_names)
    assert not numpy_loaded


# -- stamps -------------------------------------------------------------------------------
def test_results_carry_the_stamp_of_their_own_reply(mujoco_sim: Client) -> None:
    names = ground_and_balls(mujoco_sim, count=2)
    dt = mujoco_sim.status().timestep
    assert not hasattr(mujoco_sim, "last_stamp")
    stepped = mujoco_sim.step(7)
    assert stepped == Stamp(7, pytest.approx(7 * dt))
    states = mujoco_sim.get_states(names)
    assert states.stamp == stepped
    moved = mujoco_sim.set_states(names[:1], twists=np.array([[0.5, 0, 0, 0, 0, 0]]))
    assert moved == stepped  # took effect at the step it was asked at
    read = mujoco_sim.step_and_read(3, names)
    assert (read.step, read.names) == (10, names)
    assert read.sim_time == pytest.approx(10 * dt)
    assert mujoco_sim.update(names[:1], mass=2.0).step == 10
    assert mujoco_sim.delete(names[1:]).step == 10


def test_threads_sharing_a_client_each_get_their_own_stamps(mujoco_sim: Client) -> None:
    """One thread steps while another reads and writes: every stamp a call returns is the
    one its own reply carried (a shared "last stamp" would hand one thread the other's)."""
    names = ground_and_balls(mujoco_sim, count=2)
    rounds = 40

    def stepper() -> list[Stamp]:
        return [mujoco_sim.step(1) for _ in range(rounds)]

    def reader() -> list[tuple[States, Stamp]]:
        return [(mujoco_sim.get_states(names),
                 mujoco_sim.set_states(names[:1], twists=np.zeros((1, 6))))
                for _ in range(rounds)]

    with ThreadPoolExecutor(2) as pool:
        stepped, read = pool.submit(stepper), pool.submit(reader)
        steps, reads = stepped.result(), read.result()
    assert [stamp.step for stamp in steps] == list(range(1, rounds + 1))
    seen = [states.step for states, _ in reads] + [stamp.step for _, stamp in reads]
    assert all(0 <= step <= rounds for step in seen)
    for states, written in reads:
        assert states.step <= written.step  # each pair in the order it was sent


# -- timeouts -----------------------------------------------------------------------------
def test_no_timeout_means_the_registry_default_for_the_operation(mujoco_sim: Client) -> None:
    default = mujoco_sim.timeout
    assert mujoco_sim.timeout_for("status") == default
    assert mujoco_sim.timeout_for("step") == LONG_RUNNING_TIMEOUT_S
    assert mujoco_sim.timeout_for("run_until") == LONG_RUNNING_TIMEOUT_S
    for op in ("spawn", "load_model", "load_world", "delete"):
        assert mujoco_sim.timeout_for(op) == max(default, OPERATIONS[op].timeout_floor_s) > 0
    assert mujoco_sim.timeout_for("no_such_op") == default
    assert mujoco_sim.timeout_for("step", 2.5) == 2.5  # an explicit timeout wins
    assert mujoco_sim.timeout_for("spawn", 0.5) == 0.5
    assert mujoco_sim.timeout_for("status", np.int64(3)) == 3.0  # any real number


@pytest.mark.parametrize("bad", BAD_TIMEOUTS, ids=repr)
def test_a_bad_timeout_is_refused_before_anything_is_sent(mujoco_sim: Client, bad: Any) -> None:
    mujoco_sim.spawn(plane())
    before = mujoco_sim.status()
    with pytest.raises(InvalidArgumentError, match="timeout must be a finite number"):
        mujoco_sim.step(5, timeout=bad)
    with pytest.raises(InvalidArgumentError, match="above 0"):
        mujoco_sim.spawn(spheres(["b"], [[0, 0, 1]], 0.05), timeout=bad)
    with pytest.raises(InvalidArgumentError):
        mujoco_sim.call("status", timeout=bad)
    with pytest.raises(InvalidArgumentError):
        mujoco_sim.telemetry(timeout=bad)
    after = mujoco_sim.status()
    assert (after.step, after.entity_count) == (before.step, before.entity_count)


@pytest.mark.parametrize("bad", BAD_TIMEOUTS, ids=repr)
def test_a_client_with_a_bad_default_timeout_is_refused(mujoco_sim: Client, bad: Any) -> None:
    with pytest.raises(InvalidArgumentError, match="timeout"):
        Client(mujoco_sim.instance, session=mujoco_sim.session, timeout=bad)


def test_discovery_refuses_a_bad_timeout(mujoco_sim: Client) -> None:
    with pytest.raises(InvalidArgumentError):
        instances(mujoco_sim.session, 0)
    with pytest.raises(InvalidArgumentError):
        wait_for_daemon(mujoco_sim.session, mujoco_sim.instance, -1.0)
    assert mujoco_sim.instance in instances(mujoco_sim.session, 2.0)


def test_a_telemetry_wait_of_zero_is_refused(mujoco_sim: Client) -> None:
    with mujoco_sim.telemetry(timeout=5) as stream, pytest.raises(InvalidArgumentError):
        stream.next(0)


# -- unreachable versus busy --------------------------------------------------------------
@pytest.fixture
def lone_daemon() -> Iterator[EmbeddedDaemon]:
    """A daemon of this test's own, which the test may stop."""
    with EmbeddedDaemon("mujoco", instance="sdk-lone", telemetry_rate=1.0) as daemon:
        yield daemon


def test_a_stopped_daemon_is_unreachable_at_once(lone_daemon: EmbeddedDaemon) -> None:
    with Client(lone_daemon.instance, lone_daemon.endpoint, timeout=30.0) as sim:
        wait_for_daemon(sim.session, sim.instance, 30.0)
        assert sim.status().engine == "mujoco"
        lone_daemon.stop()
        started = time.monotonic()
        with pytest.raises(DaemonUnreachableError, match="no daemon serves instance 'sdk-lone'"):
            sim.step(1)
        assert time.monotonic() - started < sim.timeout / 3  # decided, not timed out


def test_a_daemon_killed_during_a_request_is_unreachable(lone_daemon: EmbeddedDaemon) -> None:
    """However long the get waited, the daemon's token is gone: not a timeout."""
    with Client(lone_daemon.instance, lone_daemon.endpoint) as sim, \
            ThreadPoolExecutor(1) as pool:
        wait_for_daemon(sim.session, sim.instance, 30.0)
        # A long timeout: the answer must come from the token vanishing, not the clock.
        waiting = pool.submit(sim.run_until, 1e6, 60.0)
        deadline = time.monotonic() + EVENT_WAIT_S
        while sim.status().step == 0:  # one round trip a look: the job has begun
            assert time.monotonic() < deadline, "the step request never started"
        assert lone_daemon.process is not None
        lone_daemon.process.kill()
        with pytest.raises(DaemonUnreachableError):
            waiting.result(90.0)


def test_a_daemon_that_does_not_answer_in_time_is_busy(mujoco_sim: Client) -> None:
    """A step request for far more sim time than the timeout allows: the daemon is alive
    (its token is there), so no reply in time is RequestTimeoutError. Other clients are
    still answered between its chunks; when its client goes, the daemon drops the job."""
    events: queue.SimpleQueue[dict[str, Any]] = queue.SimpleQueue()
    busy = Client(mujoco_sim.instance, session=mujoco_sim.session)
    with mujoco_sim.on_event(events.put):
        with busy, pytest.raises(RequestTimeoutError, match="alive but sent no reply"):
            busy.run_until(1e6, timeout=0.3)
        abandoned = _next_event(events, lambda e: e["kind"] == "job_abandoned")
    assert abandoned["client"] == busy.client_id
    assert mujoco_sim.status().state == "paused"


def _next_event(events: queue.SimpleQueue[dict[str, Any]],
                wanted: Callable[[dict[str, Any]], bool]) -> dict[str, Any]:
    deadline = time.monotonic() + EVENT_WAIT_S
    while True:
        event = events.get(timeout=max(0.0, deadline - time.monotonic()))
        if wanted(event):
            return event


# -- a closed client ----------------------------------------------------------------------
CALLS: dict[str, Callable[[Client], object]] = {
    "call": lambda c: c.call("status"),
    "request": lambda c: c.request("status"),
    "capabilities": Client.capabilities,
    "status": Client.status,
    "play": Client.play,
    "set_rtf": lambda c: c.set_rtf(1.0),
    "pause": Client.pause,
    "stop": Client.stop,
    "step": Client.step,
    "run_until": lambda c: c.run_until(1.0),
    "step_and_read": lambda c: c.step_and_read(1, ["a"]),
    "run_until_and_read": lambda c: c.run_until_and_read(1.0, ["a"]),
    "run_until_rest": lambda c: c.run_until_rest(1.0, ["a"], 0.1, 0.1),
    "reset": Client.reset,
    "load_world": lambda c: c.load_world("mujoco"),
    "get_params": Client.get_params,
    "set_params": lambda c: c.set_params({}),
    "spawn": lambda c: c.spawn(plane()),
    "load_model": lambda c: c.load_model("mjcf", text="<mujoco/>"),
    "list": Client.list,
    "get_states": Client.get_states,
    "get_bounds": Client.get_bounds,
    "get_shapes": Client.get_shapes,
    "get_entities": Client.get_entities,
    "set_states": lambda c: c.set_states(["a"]),
    "update": lambda c: c.update(["a"], mass=1.0),
    "delete": lambda c: c.delete(["a"]),
    "joints": Client.joints,
    "get_joint_states": Client.get_joint_states,
    "set_joint_states": lambda c: c.set_joint_states(["j"], 0.0),
    "set_joint_states_and_read": lambda c: c.set_joint_states_and_read(["j"], 0.0, ["a"]),
    "set_joint_targets": lambda c: c.set_joint_targets(["j"], "none"),
    "apply_wrench": lambda c: c.apply_wrench(["a"], np.zeros(6)),
    "clear_wrenches": Client.clear_wrenches,
    "step_and_read_joints": lambda c: c.step_and_read_joints(1, ["j"]),
    "step_and_read_both": lambda c: c.step_and_read_both(1, ["a"], ["j"]),
    "run_until_and_read_joints": lambda c: c.run_until_and_read_joints(1.0, ["j"]),
    "telemetry": Client.telemetry,
    "on_telemetry": lambda c: c.on_telemetry(lambda _: None),
    "on_event": lambda c: c.on_event(lambda _: None),
    "enter": Client.__enter__,
    "world": lambda c: c.world("side"),
    "list_worlds": Client.list_worlds,
    "create_world": lambda c: c.create_world("side"),
    "fork_world": lambda c: c.fork_world("side"),
    "delete_world": lambda c: c.delete_world("side"),
    "snapshot": lambda c: c.snapshot("s"),
    "restore": lambda c: c.restore("s"),
    "snapshots": Client.snapshots,
    "delete_snapshot": lambda c: c.delete_snapshot("s"),
    "predict": lambda c: c.predict(0.1),
    "compare": lambda c: c.compare(["a"], np.zeros(7)),
    "calibrate": lambda c: c.calibrate({"a.friction": (0, 1)}, ["a"], [0, 1],
                                       np.zeros((2, 1, 7))),
    "render": lambda c: c.render(camera((0, 0, 1), (0, 0, 0), up=(0, 1, 0))),
    "add_camera": lambda c: c.add_camera("cam", camera((0, 0, 1), (0, 0, 0), up=(0, 1, 0))),
    "remove_camera": lambda c: c.remove_camera("cam"),
    "cameras": Client.cameras,
    "raycast": lambda c: c.raycast([0, 0, 1], directions=[0, 0, -1]),
    "contacts": Client.contacts,
    "take_control": Client.take_control,
    "release_control": Client.release_control,
    "control": lambda c: c.control().__enter__(),
    "stream_states": lambda c: c.stream_states(10.0),
}


def test_every_public_method_is_covered_by_the_closed_client_test() -> None:
    public = {name for name, _ in inspect.getmembers(Client, inspect.isfunction)
              if not name.startswith("_")}
    assert public - set(CALLS) == {"close", "timeout_for"}


@pytest.mark.parametrize("method", sorted(CALLS))
def test_a_closed_client_refuses_every_call(mujoco_sim: Client, method: str) -> None:
    client = Client(mujoco_sim.instance, session=mujoco_sim.session)
    client.close()
    client.close()  # idempotent
    assert client.closed
    with pytest.raises(ClientClosedError, match="was closed; open a new one"):
        CALLS[method](client)
    assert mujoco_sim.status().engine == "mujoco"  # a shared session stays open


def test_a_client_that_owns_its_session_closes_it_once(daemon: EmbeddedDaemon) -> None:
    with Client(daemon.instance, daemon.endpoint) as sim:
        assert sim.status().engine == daemon.engine
    sim.close()
    assert sim.session.is_closed()
    with pytest.raises(ClientClosedError):
        sim.status()




def test_a_request_waiting_while_its_client_closes_gets_a_galton_error(daemons: dict) -> None:
    """Closing a Zenoh client while another thread's step waits ends that step with a typed
    error (ClientClosedError, or the daemon's 'client disappeared' if it came first), never
    Zenoh's own ZError."""
    import threading

    from support.daemons import start_daemon

    from galton.protocol import ClientClosedError, OperationFailedError

    daemon = start_daemon(daemons, "mujoco")
    client = Client(daemon.instance, daemon.endpoint, timeout=30)
    client.load_world("mujoco")
    client.spawn(spheres(["b"], [[0, 0, 1]], 0.05))
    errors: list[BaseException] = []

    def long_step() -> None:
        try:
            client.step(10**9, timeout=120)
        except BaseException as error:  # what it raises is the question
            errors.append(error)
    waiting = threading.Thread(target=long_step)
    waiting.start()
    with Client(daemon.instance, daemon.endpoint) as watcher:
        deadline = time.monotonic() + 30
        while watcher.status().step == 0:  # the step is under way
            assert time.monotonic() < deadline
        client.close()
        waiting.join(60)
        assert not waiting.is_alive() and len(errors) == 1
        assert isinstance(errors[0], (ClientClosedError, OperationFailedError)), errors[0]
        watcher.pause()
