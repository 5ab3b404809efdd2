"""The control lease (issue 28), on both engines and both transports: the holder changes the
world; anyone else's changes are refused with CONTROL_HELD and change nothing, reads stay
open; releasing lets the others in; a holder that is killed loses control and its step.

Every test that takes control gives it back before it ends (the daemons are shared by the
session), and waits on the daemon's own signal (an event, a status) where one is due."""

from __future__ import annotations

import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import msgpack
import pytest
from support import ball_row, companion, ground_and_balls, raw_replies, snapshot

from galton.client import Client, EmbeddedDaemon, spheres
from galton.protocol import ControlHeldError, OperationFailedError, ResultCode, decode_reply
from galton.protocol.keys import client_token_key

WAIT_S = 20.0
LONG = 10**9
# A holder in a process of its own: takes control, says so, then steps for ever.
HOLDER_SCRIPT = """
import sys
from galton.client import Client
instance, endpoint = sys.argv[1:3]
with Client(instance, endpoint, timeout=20.0) as sim:
    sim.take_control()
    print(sim.client_id, flush=True)
    sim.step(10**9, timeout=600)
"""


@pytest.fixture
def other(sim: Client) -> Iterator[Client]:
    """A second client of the same daemon over the same transport."""
    with companion(sim) as second:
        yield second


def wait_for(condition: Callable[[], bool], timeout: float = WAIT_S) -> None:
    """Poll a condition answered by the daemon (each poll is a round trip) until it holds."""
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "condition not met in time"


def next_event(events: queue.Queue[dict[str, Any]], kind: str,
               timeout: float = WAIT_S) -> dict[str, Any]:
    """The next event of this kind (others are skipped), or queue.Empty after a wait."""
    while True:
        event = events.get(timeout=timeout)
        if event["kind"] == kind:
            return event


def raw_code(client: Client, op: str, body: dict[str, Any]) -> tuple[ResultCode, str]:
    """Send an envelope as is (no client id unless it holds one) on ``client``'s transport."""
    replies = raw_replies(client, op, msgpack.packb(body, use_bin_type=True))
    assert len(replies) == 1, f"{op}: {len(replies)} replies"
    reply = decode_reply(replies[0])
    return reply.code, reply.message


def test_nobody_holds_control_at_first(sim: Client) -> None:
    assert sim.status().controller is None
    assert sim.release_control() is False  # nothing to release is no error


def test_the_holder_changes_the_world_and_others_change_nothing(sim: Client,
                                                                other: Client) -> None:
    names = ground_and_balls(sim)
    with sim.control():
        assert other.status().controller == sim.client_id
        sim.step(5)
        sim.set_params({"gravity": [0.0, 0.0, -9.0]})
        before, params = snapshot(sim), sim.get_params()
        refusals: dict[str, Callable[[], object]] = {
            "spawn": lambda: other.spawn(spheres(["intruder"], [[0, 0, 3]], radius=0.05)),
            "step": lambda: other.step(1),
            "run_until": lambda: other.run_until(1.0),
            "play": lambda: other.play(),
            "reset": lambda: other.reset("all"),
            "set_params": lambda: other.set_params({"gravity": [0.0, 0.0, 0.0]}),
            "delete": lambda: other.delete(names),
            "set_states": lambda: other.set_states(names[:1], poses=[[0, 0, 5, 1, 0, 0, 0]]),
            "predict": lambda: other.predict(0.01),
        }
        for op, attempt in refusals.items():
            with pytest.raises(ControlHeldError, match=sim.client_id) as refused:
                attempt()
            assert refused.value.details["controller"] == sim.client_id, op
        snapshot(sim).assert_same(before)
        assert sim.get_params() == params
        # Reads stay open to everyone.
        assert sorted(e.name for e in other.list()) == sorted(["ground", *names])
        assert other.get_states(names).poses.shape == (len(names), 7)
        assert other.status().step == before.step
    assert other.status().controller is None
    other.delete(names[:1])  # released: the other client is let in
    assert "ball_0" not in {e.name for e in sim.list()}


def test_control_is_contended_taken_again_and_released_by_its_holder(sim: Client,
                                                                      other: Client) -> None:
    assert sim.take_control() is True
    try:
        assert sim.take_control() is False  # taking it again changes nothing
        with pytest.raises(ControlHeldError, match=f"take_control.*{sim.client_id}"):
            other.take_control()
        with pytest.raises(ControlHeldError, match="only the holder"):
            other.release_control()
        assert other.status().controller == sim.client_id
    finally:
        assert sim.release_control() is True
    assert sim.release_control() is False
    with other.control():
        assert sim.status().controller == other.client_id
        with pytest.raises(ControlHeldError, match=other.client_id):
            sim.reset()
    assert sim.status().controller is None


def test_a_block_inside_a_block_leaves_control_held(sim: Client) -> None:
    with sim.control():
        with sim.control():
            pass
        assert sim.status().controller == sim.client_id
    assert sim.status().controller is None


def test_control_events_say_taken_and_released(sim: Client) -> None:
    events: queue.Queue[dict[str, Any]] = queue.Queue()
    with sim.on_event(events.put):
        wait_for(lambda: _heard(sim, events))  # the subscription is up (ZeroMQ joins late)
        with sim.control():
            pass
        taken, released = next_event(events, "control"), next_event(events, "control")
    assert (taken["holder"], taken["change"]) == (sim.client_id, "taken")
    assert (released["holder"], released["change"]) == (sim.client_id, "released")


def _heard(sim: Client, events: queue.Queue[dict[str, Any]]) -> bool:
    """Publish a harmless scene event and say whether it came back within a second."""
    sim.reset("time")
    try:
        next_event(events, "scene", timeout=1.0)
    except queue.Empty:
        return False
    return True


def test_requests_without_an_identity_are_refused_while_control_is_held(
        sim: Client, other: Client) -> None:
    """A raw request from the other client carries no client id: over Zenoh it is
    anonymous; over ZeroMQ its connection names it, and it is not the holder's."""
    ground_and_balls(sim, 1)
    step = {"v": 1, "op": "step", "args": {"count": 1}}
    status = {"v": 1, "op": "status", "args": {}}
    with sim.control():
        before = snapshot(sim)
        code, message = raw_code(other, "step", step)
        assert code == ResultCode.CONTROL_HELD and sim.client_id in message
        assert raw_code(other, "status", status)[0] == ResultCode.OK
        snapshot(sim).assert_same(before)
    assert raw_code(other, "step", step)[0] == ResultCode.OK


def test_take_control_needs_an_identity(sim: Client, other: Client) -> None:
    """Over Zenoh a take_control without client is refused; over ZeroMQ the connection is
    the holder, and the lease ends when that connection closes."""
    take = {"v": 1, "op": "take_control", "args": {}}
    code, message = raw_code(other, "take_control", take)
    if sim.transport.kind == "zenoh":
        assert code == ResultCode.INVALID_ARGUMENT and "'client'" in message
        assert sim.status().controller is None
        return
    assert code == ResultCode.OK
    holder = sim.status().controller
    assert holder is not None and holder.startswith("@zmq:")
    with pytest.raises(ControlHeldError, match=holder):
        sim.step(1)
    other.close()  # the connection control was taken on closes
    wait_for(lambda: sim.status().controller is None)
    sim.step(1)


def test_a_killed_holder_loses_control_and_its_step(sim: Client, daemon: EmbeddedDaemon,
                                                    transport: str) -> None:
    """A holder in a separate process takes control and starts a long step; SIGKILL ends
    its token (Zenoh) or its connection (ZeroMQ): the step ends and control is lost."""
    sim.spawn(ball_row(1)[1])
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint
    events: queue.Queue[dict[str, Any]] = queue.Queue()
    with sim.on_event(events.put):
        with subprocess.Popen([sys.executable, "-c", HOLDER_SCRIPT, daemon.instance,
                               str(endpoint)], stdout=subprocess.PIPE, text=True) as holder:
            try:
                assert holder.stdout is not None
                holder_id = holder.stdout.readline().strip()  # printed once it holds control
                assert holder_id, "the holder process ended before it took control"
                assert sim.status().controller == holder_id
                wait_for(lambda: sim.status().step > 0)  # its step runs
                with pytest.raises(ControlHeldError, match=holder_id):
                    sim.pause()
            finally:
                holder.send_signal(signal.SIGKILL)
        abandoned, lost = next_event(events, "job_abandoned"), next_event(events, "control")
    assert abandoned["client"] == holder_id and 0 < abandoned["steps_done"] < LONG
    assert (lost["holder"], lost["change"]) == (holder_id, "lost")
    status = sim.status()
    assert status.controller is None and status.state == "paused"
    sim.step(1)  # the world is free again, and no step job runs
    assert sim.status().step == status.step + 1


def test_a_made_up_client_id_cannot_take_control(sim: Client, transport: str) -> None:
    """Over Zenoh the lease is tied to the client's liveliness token: an id with no token
    would hold control for ever, so it is refused (over ZeroMQ the connection names the
    taker, whatever id it gives)."""
    payload = msgpack.packb({"v": 1, "op": "take_control", "args": {},
                             "client": "made-up-client-id"}, use_bin_type=True)
    reply = decode_reply(raw_replies(sim, "take_control", payload)[0])
    if transport == "zenoh":
        assert reply.code == ResultCode.INVALID_ARGUMENT and "liveliness" in reply.message
        assert sim.status().controller is None
    else:
        assert reply.ok and sim.status().controller == "made-up-client-id"
        sim.release_control()  # the same connection: the holder's
        assert sim.status().controller is None


@pytest.mark.parametrize("client_id", ["*", "**", "a/b", "bad?id", "bad#id", "$*"])
def test_a_client_id_that_is_no_single_token_name_cannot_take_control(
        sim: Client, transport: str, client_id: str) -> None:
    """Over Zenoh a ``client`` with a wildcard would find any client's token alive (and no
    token's going would ever name it), and one with '/', '?' or '#' names no token at all:
    each is INVALID_ARGUMENT, naming the id, and nobody holds control."""
    if transport != "zenoh":
        pytest.skip("over ZeroMQ the connection names the taker, whatever id it gives")
    payload = msgpack.packb({"v": 1, "op": "take_control", "args": {}, "client": client_id},
                            use_bin_type=True)
    reply = decode_reply(raw_replies(sim, "take_control", payload)[0])
    assert reply.code == ResultCode.INVALID_ARGUMENT, (reply.code, reply.message)
    assert repr(client_id) in reply.message
    assert sim.status().controller is None


def test_over_zeromq_a_zenoh_token_named_like_the_holder_ends_nothing(
        sim: Client, daemon: EmbeddedDaemon, transport: str) -> None:
    """Over ZeroMQ control and a long step are tied to their connection, not to a Zenoh
    token: a token named after the holder's id (anyone on Zenoh may declare one, a viewer
    too, and status shows the id) that comes and goes ends neither."""
    if transport != "zmq":
        pytest.skip("over Zenoh the holder's own token is what ties control")
    sim.spawn(ball_row(1)[1])
    outcome: list[BaseException | None] = []

    def step_long() -> None:
        try:
            sim.step(LONG, timeout=600)
            outcome.append(None)
        except BaseException as error:  # the pause below ends it
            outcome.append(error)
    with sim.control():
        stepper = threading.Thread(target=step_long, daemon=True)
        stepper.start()
        wait_for(lambda: sim.status().step > 0)
        with Client(daemon.instance, daemon.endpoint, timeout=20.0) as spoofer:
            token = spoofer.session.liveliness().declare_token(client_token_key(sim.client_id))
            spoofer.capabilities()  # the daemon has seen the token (same link, in order)
            token.undeclare()
            spoofer.capabilities()  # ... and its going
        status = sim.status()
        assert status.controller == sim.client_id
        assert stepper.is_alive() and not outcome
        wait_for(lambda: sim.status().step > status.step)  # the step still runs
        sim.pause()
        stepper.join(WAIT_S)
    assert isinstance(outcome[0], OperationFailedError) and "pause" in str(outcome[0])
