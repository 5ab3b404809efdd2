"""State streams (docs/protocol.md, "State streams"): transport semantics, so once per
transport on one engine (MuJoCo)."""

from __future__ import annotations

import time

import msgpack
import numpy as np
import pytest
from support import companion, raw_replies

from galton.client import Client, spheres
from galton.client.sdk.streams import StateStream
from galton.protocol import (
    PROTOCOL_VERSION,
    InvalidArgumentError,
    NotFoundError,
    ResourceLimitError,
    ResultCode,
    decode_reply,
)

pytestmark = pytest.mark.parametrize("engine", ["mujoco"])

RATE_HZ = 20.0


def _balls(sim: Client) -> list[str]:
    names = ["red_0", "red_1", "red_2"]
    sim.spawn(spheres(names, [[0.0, 0.0, 1.0], [0.2, 0.0, 1.0], [0.4, 0.0, 1.0]],
                      radius=0.05, tags=["red"]))
    return names


def test_a_stream_carries_every_entity_at_the_rate_asked_while_playing(sim: Client) -> None:
    names = _balls(sim)
    sim.play()
    try:
        with sim.stream_states(rate=RATE_HZ, timeout=10.0) as stream:
            first = stream.next()
            started = time.monotonic()
            samples = [stream.next() for _ in range(10)]
            elapsed = time.monotonic() - started
    finally:
        sim.pause()
    assert set(first.names) == set(names)
    assert all(s.poses.shape == (3, 7) for s in samples)
    assert [s.seq for s in samples] == sorted({s.seq for s in samples})
    assert samples[-1].sim_time > first.sim_time
    assert samples[-1].state == "playing"
    # Ten periods at 20 Hz: 0.5 s; a loaded machine may be late, never this early.
    assert 10 / RATE_HZ * 0.6 <= elapsed <= 10 / RATE_HZ * 4
    falling = samples[-1].poses[:, 2]
    assert np.all(falling < 1.0)  # the balls fell while the stream watched


def test_a_named_stream_carries_those_poses_as_get_states_reads_them(sim: Client) -> None:
    names = _balls(sim)
    sim.step(50)
    with sim.stream_states(rate=RATE_HZ, names=["red_2", "red_0"], timeout=10.0) as stream:
        sample = stream.next()
    assert sample.names == ("red_2", "red_0")
    read = sim.get_states(["red_2", "red_0"])
    np.testing.assert_array_equal(sample.poses, read.poses)
    assert sample.step == 50 and sample.state != "playing"
    assert len(names) == 3


@pytest.mark.parametrize(("args", "error", "says"), [
    ({"rate": 0}, InvalidArgumentError, "rate"),
    ({"rate": 61}, InvalidArgumentError, "rate"),
    ({"rate": "fast"}, InvalidArgumentError, "rate"),
    ({"rate": 10, "names": ["nobody"]}, NotFoundError, "nobody"),
    ({"rate": 10, "world": "nowhere"}, NotFoundError, "nowhere"),
    ({"rate": 10, "nmaes": ["red_0"]}, InvalidArgumentError, "names"),
])
def test_bad_stream_requests_are_refused_and_change_nothing(
        sim: Client, args: dict[str, object], error: type[Exception], says: str) -> None:
    _balls(sim)
    before = sim.get_states()
    with pytest.raises(error, match=says):
        sim.call("stream_states", args)
    after = sim.get_states()
    np.testing.assert_array_equal(before.poses, after.poses)
    assert sim.status().step == 0


def test_only_its_client_closes_a_stream_and_an_unknown_one_is_not_found(
        sim: Client, daemon: object, transport: str) -> None:
    _balls(sim)
    opened = sim.call("stream_states", {"rate": 5})
    with pytest.raises(NotFoundError, match="no stream"):
        sim.call("close_stream", {"stream": "0123456789abcdef"})
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint  # type: ignore[attr-defined]
    with Client(sim.instance, endpoint, timeout=20.0) as other, \
            pytest.raises(NotFoundError, match="no stream"):
        other.call("close_stream", {"stream": opened["stream"]})
    assert sim.call("close_stream", {"stream": opened["stream"]})["closed"] is True


def test_a_side_world_stream_ends_with_a_sample_that_says_why_when_it_is_deleted(
        sim: Client) -> None:
    _balls(sim)
    sim.fork_world("ahead")
    try:
        with sim.world("ahead").stream_states(rate=RATE_HZ, timeout=10.0) as stream:
            assert stream.next().world == "ahead"
            sim.delete_world("ahead")
            last = stream.next()
            while last.ended is None:
                last = stream.next()
    finally:
        if "ahead" in [w.name for w in sim.list_worlds()]:
            sim.delete_world("ahead")
    assert "deleted" in last.ended


def test_a_stream_ends_with_a_sample_that_says_why_when_its_client_goes(
        sim: Client, daemon: object, transport: str) -> None:
    """Watched by another client on its key, a stream whose client goes ends with a last
    sample saying so, over either transport (the Zenoh token, the ZeroMQ connection)."""
    _balls(sim)
    endpoint = daemon.endpoint if transport == "zenoh" else daemon.zmq_endpoint  # type: ignore[attr-defined]
    other = Client(sim.instance, endpoint, timeout=20.0)
    try:
        opened = other.call("stream_states", {"rate": RATE_HZ})
        watched = StateStream(other, sim.transport, opened, None, 10.0)
    except BaseException:
        other.close()
        raise
    with watched:
        assert watched.next().stream == opened["stream"]
        other.close()
        last = watched.next()
        while last.ended is None:
            last = watched.next()
    assert last.ended == "its client went" and len(last.poses) == 0


@pytest.mark.parametrize("client_id", ["*", "**", "$*", "a/b", "@ctl", "a*", "x y", "?q"])
def test_a_wildcard_or_key_expression_is_no_client_id(sim: Client, client_id: str) -> None:
    """Issue 46: ``client: "*"`` opened a stream every client's token kept alive, for good."""
    payload = msgpack.packb({"v": PROTOCOL_VERSION, "op": "stream_states",
                             "args": {"rate": 5}, "client": client_id})
    replies = raw_replies(sim, "stream_states", payload)
    assert len(replies) == 1
    reply = decode_reply(replies[0])
    assert reply.code == ResultCode.INVALID_ARGUMENT and "client id" in reply.message


def test_the_stream_pool_is_shared_and_its_refusals_name_their_limit(sim: Client) -> None:
    """One client holds at most 8 of the 32 streams; each refusal is RESOURCE_LIMIT with
    ``details.limit`` naming the limit and ``details.max`` its value (docs/protocol.md)."""
    others = [companion(sim) for _ in range(4)]
    try:
        opened = [sim.call("stream_states", {"rate": 1}) for _ in range(8)]
        with pytest.raises(ResourceLimitError) as mine:
            sim.call("stream_states", {"rate": 1})
        assert mine.value.details == {"limit": "max_streams_per_client", "max": 8}
        for other in others[:3]:
            for _ in range(8):
                other.call("stream_states", {"rate": 1})
        with pytest.raises(ResourceLimitError) as pool:
            others[3].call("stream_states", {"rate": 1})
        assert pool.value.details == {"limit": "max_streams", "max": 32}
        sim.call("close_stream", {"stream": opened[0]["stream"]})
        others[3].call("stream_states", {"rate": 1})  # a freed place is anyone's
    finally:
        for other in others:
            other.close()
    for stream in opened[1:]:
        sim.call("close_stream", {"stream": stream["stream"]})
