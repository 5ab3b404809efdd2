"""Nothing a client sends stops, corrupts or starves the daemon (issue 22): each case found
by hand or by the fuzzer, on both engines, through a real daemon."""

from __future__ import annotations

import queue
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import msgpack
import numpy as np
import pytest
from support import ball_row, companion, raw_replies, send_over_the_edge, snapshot

from galton.client import Client, plane, spheres
from galton.daemon.engines.check.refusals import PROBE_MODELS
from galton.protocol import (
    ClientClosedError,
    IncorrectStateError,
    InvalidArgumentError,
    NotFoundError,
    OperationFailedError,
    PhysicsError,
    ResultCode,
    decode_reply,
)

WAIT_S = 20.0
ONE_BODY_MJCF = ('<mujoco><worldbody><body name="b"><freejoint/><geom size=".1"/></body>'
                 "</worldbody></mujoco>")
LONG = 10**9


def raw(sim: Client, op: str, body: Any, timeout: float = 10.0) -> tuple[int, str, int]:
    """Send a raw payload; return (code, message, reply size): exactly one reply must come."""
    payload = body if isinstance(body, bytes) else msgpack.packb(body, use_bin_type=True)
    replies = raw_replies(sim, op, payload, timeout)
    assert len(replies) == 1, f"{op}: no reply"
    data = replies[0]
    reply = decode_reply(data)
    return reply.code, reply.message, len(data)


def request(op: str, args: Any) -> dict[str, Any]:
    return {"v": 1, "op": op, "args": args}


def diverge(sim: Client) -> None:
    """Drive the world to PHYSICS_ERROR, as a client can."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    send_over_the_edge(sim)
    with pytest.raises(PhysicsError):
        sim.step(5)


class Background:
    """A call made on another thread; ``result()`` waits for it with a timeout."""

    def __init__(self, call: Callable[[], Any]) -> None:
        self._out: queue.Queue[tuple[bool, Any]] = queue.Queue()
        threading.Thread(target=self._run, args=(call,), daemon=True).start()

    def _run(self, call: Callable[[], Any]) -> None:
        try:
            self._out.put((True, call()))
        except Exception as exc:
            self._out.put((False, exc))

    def result(self, timeout: float = WAIT_S) -> Any:
        ok, value = self._out.get(timeout=timeout)
        if not ok:
            raise value
        return value


def wait_for(condition: Callable[[], bool], timeout: float = WAIT_S) -> None:
    """Poll a condition answered by the daemon (each poll is a round trip) until it holds."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"


@pytest.fixture
def long_step(sim: Client) -> Iterator[tuple[Background, Client]]:
    """A step of 10^9 running on the daemon, asked by a second client; paused at the end."""
    sim.spawn(ball_row(1)[1])
    other = companion(sim)
    job = Background(lambda: other.step(LONG, timeout=120))
    wait_for(lambda: sim.status().step > 0)
    yield job, other
    sim.pause()
    other.close()


# -- the daemon exited ---------------------------------------------------------------------
def test_play_on_a_diverged_world_is_refused_and_the_daemon_serves_on(sim: Client) -> None:
    diverge(sim)
    with pytest.raises(PhysicsError, match="reset"):
        sim.play()
    status = sim.status()
    assert (status.state, status.faulted) == ("paused", True)
    sim.reset("state")
    assert sim.play().state == "playing"
    sim.pause()


def test_a_world_diverging_while_playing_pauses_and_the_daemon_serves_on(sim: Client) -> None:
    """get_states notices the divergence before the loop's own check does: the world must
    pause then too, not step on (the daemon used to exit here)."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    send_over_the_edge(sim)
    sim.play(rtf=0)
    wait_for(lambda: sim.status().step > 0)  # its first step carries it past the limits
    with pytest.raises(PhysicsError):
        sim.get_states(["ball"])
    status = sim.status()
    assert (status.state, status.faulted) == ("paused", True)
    sim.reset("time")
    assert sim.status().faulted
    with pytest.raises(PhysicsError):
        sim.step(1)
    sim.reset("state")
    assert sim.step(2).step == 2


def test_a_diverged_state_set_by_a_request_is_refused_where_it_is_set(sim: Client) -> None:
    """A state beyond the world's limits is refused by the request that sets it (issue 35:
    a read never faults the world)."""
    sim.spawn(plane(), spheres(["ball"], [[0, 0, 0.5]], 0.05))
    with pytest.raises(InvalidArgumentError, match="limit"):
        sim.set_states(["ball"], poses=np.array([[4e299, 0, 0.5, 0, 0, 0, 1]]))
    np.testing.assert_array_equal(sim.get_states(["ball"]).positions, [[0, 0, 0.5]])
    assert not sim.status().faulted


# -- rejected yet applied --------------------------------------------------------------------
def test_play_refused_during_a_step_leaves_the_target_rtf(sim: Client, long_step: Any) -> None:
    before = sim.status().target_rtf
    with pytest.raises(IncorrectStateError):
        sim.play(rtf=7.5)
    assert sim.status().target_rtf == before


def test_a_bad_reset_scope_during_a_step_leaves_the_step_running(sim: Client,
                                                                 long_step: Any) -> None:
    job, _ = long_step
    code, message, _ = raw(sim, "reset", request("reset", {"scope": "bogus"}))
    assert code == ResultCode.INVALID_ARGUMENT and "bogus" in message
    step = sim.status().step
    wait_for(lambda: sim.status().step > step)
    sim.pause()
    with pytest.raises(OperationFailedError, match="paused"):
        job.result()


def test_a_huge_mass_update_is_refused_and_changes_nothing(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    before = snapshot(sim)
    code, _, _ = raw(sim, "update", request("update", {"names": names[:1],
                                                       "properties": {"mass": 1e-300}}))
    if code == ResultCode.OK:  # an engine may take it: then it must simulate on
        sim.step(10)
    else:
        assert code == ResultCode.INVALID_ARGUMENT
        snapshot(sim).assert_same(before)
    sim.delete(names[1:])  # a recompile with the refused body still there
    sim.spawn(ball_row(1, prefix="more")[1])
    assert sim.step(3).step > 0
    sim.delete(names[:1])


# -- wrong or missing replies -----------------------------------------------------------------
def nested(depth: int) -> Any:
    value: Any = 1
    for _ in range(depth):
        value = [value]
    return value


@pytest.mark.parametrize("depth", [1000, 1015])
def test_deep_nesting_gets_a_resource_limit_reply(sim: Client, depth: int) -> None:
    code, message, _ = raw(sim, "spawn", request("spawn", {"groups": nested(depth)}))
    assert code == ResultCode.RESOURCE_LIMIT and "deeper" in message
    code, _, _ = raw(sim, "status", request("status", {"world": nested(depth)}))
    assert code == ResultCode.RESOURCE_LIMIT


def test_run_until_far_away_is_refused_naming_its_own_field(sim: Client) -> None:
    sim.spawn(ball_row(1)[1])
    for target in (1e308, 1e7):
        code, message, _ = raw(sim, "run_until", request("run_until", {"sim_time": target}))
        assert code == ResultCode.INVALID_ARGUMENT
        assert "run_until.sim_time" in message and "step.count" not in message
    assert sim.status().step == 0


def one_body(sim: Client) -> tuple[str, str]:
    """A one-body model in a format the engine loads (MJCF where it can)."""
    if "mjcf" in sim.capabilities().model_formats:
        return "mjcf", ONE_BODY_MJCF
    return "urdf", PROBE_MODELS["urdf"]


@pytest.mark.parametrize("prefix", ["\x00", "a\nb", "x" * 65])
def test_a_bad_model_prefix_is_an_invalid_argument(sim: Client, prefix: str) -> None:
    fmt, text = one_body(sim)
    code, message, _ = raw(sim, "load_model", request(
        "load_model", {"format": fmt, "text": text, "prefix": prefix}))
    assert code == ResultCode.INVALID_ARGUMENT and "prefix" in message
    assert sim.list() == []


def test_a_taken_model_name_is_name_not_unique(sim: Client) -> None:
    fmt, text = one_body(sim)
    sim.load_model(fmt, text=text, prefix="m_")
    before = snapshot(sim)
    code, _, _ = raw(sim, "load_model", request(
        "load_model", {"format": fmt, "text": text, "prefix": "m_"}))
    assert code == ResultCode.NAME_NOT_UNIQUE
    snapshot(sim).assert_same(before)


# -- exhaustion --------------------------------------------------------------------------------
@pytest.mark.parametrize("path", ["/dev/stdin", "/dev/zero", "/tmp", "/no/such/model.urdf"])
def test_load_model_reads_only_regular_files(sim: Client, path: str) -> None:
    code, message, _ = raw(sim, "load_model", request(
        "load_model", {"format": one_body(sim)[0], "path": path}), timeout=5)
    assert code == ResultCode.INVALID_ARGUMENT and "load_model.path" in message
    assert sim.status().entity_count == 0


def test_a_request_over_the_size_limit_is_refused_before_decoding(sim: Client) -> None:
    code, message, size = raw(sim, "list", request("list", {"name": b"x" * (17 << 20)}))
    assert code == ResultCode.RESOURCE_LIMIT and "bytes" in message
    assert size < 4096


def test_a_big_field_is_never_echoed(sim: Client) -> None:
    code, message, size = raw(sim, "list", request("list", {"name": b"x" * (1 << 20)}))
    assert code == ResultCode.INVALID_ARGUMENT and "list.name" in message
    assert size < 4096


def test_a_long_string_is_a_resource_limit(sim: Client) -> None:
    code, _, size = raw(sim, "delete", request("delete", {"names": ["n" * 100_000]}))
    assert code == ResultCode.RESOURCE_LIMIT and size < 4096


@pytest.mark.parametrize("args", [
    {"groups": [], "junk": b"x" * 1000},
    {"gruops": []},
])
def test_unknown_arguments_are_refused_with_a_suggestion(sim: Client, args: dict) -> None:
    code, message, size = raw(sim, "spawn", request("spawn", args))
    assert code == ResultCode.INVALID_ARGUMENT and "takes no field" in message
    assert size < 4096
    if "gruops" in args:
        assert "did you mean 'groups'" in message


def test_an_unknown_group_field_is_refused(sim: Client) -> None:
    group = ball_row(1)[1].to_wire()
    group["colour"] = "red"
    code, message, _ = raw(sim, "spawn", request("spawn", {"groups": [group]}))
    assert code == ResultCode.INVALID_ARGUMENT and "colour" in message
    assert sim.list() == []


def test_an_unknown_envelope_field_is_malformed(sim: Client) -> None:
    code, _, _ = raw(sim, "status", {"v": 1, "op": "status", "args": {}, "extra": 1})
    assert code == ResultCode.MALFORMED_REQUEST


# -- events and long steps -------------------------------------------------------------------
def test_events_carry_a_sequence_and_reset_is_a_scene_event(sim: Client) -> None:
    events: queue.Queue[dict] = queue.Queue()
    with sim.on_event(events.put):
        sim.spawn(ball_row(1)[1])
        sim.reset("all")
        seen = []
        while not any(e.get("op") == "reset" for e in seen):
            seen.append(events.get(timeout=WAIT_S))
    seqs = [e["seq"] for e in seen]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
    assert [e["op"] for e in seen if e["kind"] == "scene"][-2:] == ["spawn", "reset"]


def test_deleting_what_a_step_reads_answers_the_step_at_once(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    other = companion(sim)
    job = Background(lambda: other.step_and_read(LONG, names[:1], timeout=120))
    wait_for(lambda: sim.status().step > 0)
    sim.delete(names[:1])
    with pytest.raises(NotFoundError, match="deleted") as caught:
        job.result()
    assert 0 < caught.value.details["steps_done"] < LONG
    assert sim.play().state == "playing"
    sim.pause()
    other.close()


def test_a_vanished_client_s_step_ends(sim: Client) -> None:
    """A Zenoh client holds a liveliness token, a ZeroMQ one a connection; when it goes,
    its step request ends. (The Zenoh companion shares the session, which stays open, so
    its waiting thread hears why; the ZeroMQ one's closed socket ends its wait at once.)"""
    sim.spawn(ball_row(1)[1])
    events: queue.Queue[dict] = queue.Queue()
    other = companion(sim)
    with sim.on_event(events.put):
        job = Background(lambda: other.step(LONG, timeout=120))
        wait_for(lambda: sim.status().step > 0)
        other.close()  # withdraws its token, as a killed process's session does
        event = events.get(timeout=WAIT_S)
        while event["kind"] != "job_abandoned":
            event = events.get(timeout=WAIT_S)
    assert event["client"] == other.client_id and 0 < event["steps_done"] < LONG
    assert sim.play().state == "playing"
    sim.pause()
    expected = (ClientClosedError, "closed") if sim.transport.kind == "zmq" else (
        OperationFailedError, "client disappeared")
    with pytest.raises(expected[0], match=expected[1]):
        job.result()


# -- what the document says ------------------------------------------------------------------
def test_quaternions_come_back_with_one_sign(sim: Client) -> None:
    names, group = ball_row(2)
    sim.spawn(group)
    sent = np.array([[0, 0, 1, 0, 0, 0.6, -0.8], [1, 0, 1, 0.6, 0, 0.8, 0]])
    sim.set_states(names, poses=sent)
    quats = sim.get_states(names).poses[:, 3:]
    np.testing.assert_allclose(quats, [[0, 0, -0.6, 0.8], [0.6, 0, 0.8, 0]], atol=1e-9)


def test_list_reports_effective_values(sim: Client) -> None:
    sim.spawn(plane(), ball_row(1)[1])
    for info in sim.list():
        assert info.friction is not None and info.restitution is not None
        assert (info.mass is None) == info.static
    ball = sim.list(kind="dynamic")[0]
    assert ball.mass == pytest.approx(1000 * 4 / 3 * np.pi * 0.05**3, rel=1e-6)


def test_a_killed_client_process_s_step_ends(sim: Client, daemon: Any) -> None:
    """The issue's case: a client process killed during step 10^9."""
    sim.spawn(ball_row(1)[1])
    script = ("import sys\nfrom galton.client import Client\n"
              "with Client(sys.argv[1], sys.argv[2], timeout=5) as c:\n"
              "    c.step(10**9, timeout=600)\n")
    events: queue.Queue[dict] = queue.Queue()
    with sim.on_event(events.put):
        child = subprocess.Popen([sys.executable, "-c", script, daemon.instance,
                                  daemon.endpoint])
        try:
            wait_for(lambda: sim.status().step > 0)
        finally:
            child.kill()
            child.wait(WAIT_S)
        event = events.get(timeout=WAIT_S)
        while event["kind"] != "job_abandoned":
            event = events.get(timeout=WAIT_S)
    assert 0 < event["steps_done"] < LONG
    assert sim.play().state == "playing"
    sim.pause()
