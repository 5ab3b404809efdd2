"""Time control through a real daemon: step, pause, play, run_until, reset, stop."""

from __future__ import annotations

import numpy as np
import pytest
from support import ball_row, companion, ground_and_balls

from galton.client import Client, plane, spheres
from galton.protocol import (
    BodyGroup,
    IncorrectStateError,
    InvalidArgumentError,
    OperationFailedError,
    ResultCode,
)

RTF_TOLERANCE = 0.05


def test_a_new_world_is_stopped_at_zero(sim: Client) -> None:
    status = sim.status()
    assert (status.state, status.step, status.sim_time) == ("stopped", 0, 0.0)


@pytest.mark.parametrize("count", [1, 7, 250])
def test_step_advances_exactly_n(sim: Client, count: int) -> None:
    ground_and_balls(sim)
    before = sim.status()
    stamp = sim.step(count)
    after = sim.status()
    assert stamp.step == after.step == before.step + count
    assert after.sim_time == pytest.approx(before.sim_time + count * after.timestep)
    assert after.state == "paused"


def test_identical_runs_give_identical_states(sim: Client) -> None:
    runs = []
    for _ in range(2):
        sim.reset("all")
        names = ground_and_balls(sim, count=20)
        sim.set_states(names, twists=np.tile([0.3, 0.1, 0, 0, 0, 0.5], (20, 1)))
        sim.step(300)
        runs.append(sim.get_states(names))
    assert np.array_equal(runs[0].poses, runs[1].poses)
    assert np.array_equal(runs[0].twists, runs[1].twists)


def test_mutating_replies_carry_the_step_they_took_effect_at(sim: Client) -> None:
    sim.step(10)
    reply = sim.request("spawn", {"groups": [spheres(["late"], [[0, 0, 1]], 0.05).to_wire()]})
    assert reply.ok and reply.result["names"] == ["late"]
    assert reply.step == 10
    assert reply.sim_time == pytest.approx(10 * sim.status().timestep)


def test_pause_stops_the_clock(sim: Client) -> None:
    ground_and_balls(sim)
    with sim.telemetry(timeout=5) as stream:
        sim.play(0.0)
        _wait_for(stream, lambda t: t.state == "playing" and t.sim_time > 0)
        paused = sim.pause()
        _wait_for(stream, lambda t: t.state == "paused")
        later = [stream.next(5) for _ in range(3)]
    assert all(t.sim_time == paused.sim_time and t.state == "paused" for t in later)
    assert sim.status().sim_time == paused.sim_time


def test_play_at_real_time_tracks_the_wall_clock(sim: Client) -> None:
    ground_and_balls(sim)
    with sim.telemetry(timeout=5) as stream:
        sim.play(1.0)
        first = _wait_for(stream, lambda t: t.state == "playing" and t.sim_time > 0)
        last = _wait_for(stream, lambda t: t.wall_time - first.wall_time >= 2.0)
    sim.pause()
    rtf = (last.sim_time - first.sim_time) / (last.wall_time - first.wall_time)
    assert rtf == pytest.approx(1.0, rel=RTF_TOLERANCE)
    assert last.target_rtf == 1.0


def _wait_for(stream, predicate):  # type: ignore[no-untyped-def]
    for _ in range(200):
        sample = stream.next(5)
        if predicate(sample):
            return sample
    raise AssertionError("telemetry never met the condition")


def test_step_while_playing_is_an_incorrect_state(sim: Client) -> None:
    sim.play(1.0)
    with pytest.raises(IncorrectStateError, match="pause first"):
        sim.step(1)
    sim.pause()


def test_run_until_reaches_the_sim_time(sim: Client) -> None:
    stamp = sim.run_until(0.5)
    dt = sim.status().timestep
    assert 0.5 - 1e-9 <= stamp.sim_time < 0.5 + dt
    with pytest.raises(InvalidArgumentError, match="not after"):
        sim.run_until(0.1)


def test_reset_time_keeps_states(sim: Client) -> None:
    names, group = ball_row(1, z=3)
    sim.spawn(group)
    sim.step(50)
    moved = sim.get_states(names).poses
    status = sim.reset("time")
    assert (status.step, status.sim_time) == (0, 0.0)
    assert np.array_equal(sim.get_states(names).poses, moved)


def test_reset_state_restores_created_states(sim: Client) -> None:
    names, group = ball_row(2, z=3)
    sim.spawn(group)
    sim.step(50)
    sim.reset("state")
    np.testing.assert_allclose(sim.get_states(names).poses, group.poses, atol=1e-9)
    np.testing.assert_allclose(sim.get_states(names).twists, 0.0, atol=1e-9)
    assert sim.status().step == 50


def test_reset_spawned_removes_entities_and_keeps_time(sim: Client) -> None:
    ground_and_balls(sim)
    sim.step(5)
    status = sim.reset("spawned")
    assert status.entity_count == 0 and status.step == 5


def test_reset_all_empties_and_rewinds(sim: Client) -> None:
    ground_and_balls(sim)
    sim.step(5)
    status = sim.reset("all")
    assert (status.entity_count, status.step, status.sim_time) == (0, 0, 0.0)


def test_stop_rewinds_and_keeps_entities(sim: Client) -> None:
    names, group = ball_row(1, z=3)
    sim.spawn(group)
    sim.step(40)
    status = sim.stop()
    assert (status.state, status.step, status.entity_count) == ("stopped", 0, 1)
    np.testing.assert_allclose(sim.get_states(names).poses, group.poses, atol=1e-9)


def _colliding_balls(sim: Client) -> tuple[list[str], BodyGroup]:
    """Six balls dropped onto a ground, touching their neighbours and pushed along the row:
    contacts, collisions and rolling in the first few hundred steps."""
    sim.spawn(plane())
    names, group = ball_row(6, z=0.3)
    group.poses[:, 0] = np.linspace(0.0, 0.45, 6)
    group.twists = np.tile([0.5, 0.0, 0.0, 0.0, 0.0, 0.0], (6, 1))
    sim.spawn(group)
    return names, group


def test_a_stopped_world_replays_the_same_trajectory(sim: Client) -> None:
    """stop rewinds to the created state: the same steps then give the same states, bit
    for bit, contacts and collisions included (a model run ahead of reality must be
    repeatable)."""
    names, group = _colliding_balls(sim)
    runs = []
    for _ in range(2):
        sim.step(333)
        states = sim.get_states(names)
        runs.append((states.poses, states.twists))
        sim.stop()
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert not np.allclose(runs[0][0][:, :3], group.poses[:, :3], atol=1e-3)  # they moved


def test_how_steps_are_split_into_requests_does_not_change_the_trajectory(
        sim: Client) -> None:
    """One step(300) and 300 step(1) requests give the same states, bit for bit: the
    daemon's chunking and the engines' periodic work follow the world's steps, not the
    requests."""
    names, _ = _colliding_balls(sim)
    sim.step(300)
    whole = sim.get_states(names)
    sim.stop()
    for _ in range(300):
        sim.step(1)
    pieces = sim.get_states(names)
    np.testing.assert_array_equal(whole.poses, pieces.poses)
    np.testing.assert_array_equal(whole.twists, pieces.twists)


def test_a_long_step_is_interrupted_by_pause(sim: Client) -> None:
    ground_and_balls(sim)
    with pytest.raises(OperationFailedError, match="interrupted"):
        _step_and_pause(sim)
    assert sim.status().state == "paused"


def _step_and_pause(sim: Client) -> None:
    import threading


    started = threading.Event()

    def pause_when_running() -> None:
        with companion(sim) as other, other.telemetry() as stream:
            started.set()
            _wait_for(stream, lambda t: t.step > 0)
            other.pause()

    thread = threading.Thread(target=pause_when_running)
    thread.start()
    started.wait(5)
    try:
        sim.step(100_000_000, timeout=60)
    finally:
        thread.join(30)


def test_set_rtf_changes_the_target_not_the_state(sim: Client) -> None:
    status = sim.set_rtf(2.5)
    assert (status.target_rtf, status.state) == (2.5, "stopped")
    assert sim.play().target_rtf == 2.5
    sim.pause()


def test_step_and_read_returns_the_states_after_the_last_step(sim: Client) -> None:
    names = ground_and_balls(sim, count=5)
    states = sim.step_and_read(40, names[1:4])
    status = sim.status()
    assert states.step == status.step == 40
    assert states.names == names[1:4]
    again = sim.get_states(names[1:4])
    assert np.array_equal(states.poses, again.poses)
    assert np.array_equal(states.twists, again.twists)
    states = sim.run_until_and_read(status.sim_time + 0.2, names)
    assert states.sim_time == pytest.approx(status.sim_time + 0.2)
    assert np.array_equal(states.poses, sim.get_states(names).poses)


@pytest.mark.parametrize("read", [["ball_0", "nobody"], "ball_0", [], [1]])
def test_a_bad_read_list_rejects_the_step_before_any_step(sim: Client, read: object) -> None:
    ground_and_balls(sim, count=2)
    before = sim.status().step
    reply = sim.request("step", {"count": 10, "read": read})
    assert reply.code in (ResultCode.NOT_FOUND, ResultCode.INVALID_ARGUMENT)
    assert "read" in reply.message or "nobody" in reply.message
    assert sim.status().step == before


def test_run_until_rest_stops_once_the_bodies_rest(sim: Client) -> None:
    names = ground_and_balls(sim, count=3)
    states, at_rest = sim.run_until_rest(10.0, names, speed=0.05, every=0.25)
    assert at_rest
    assert states.sim_time < 10.0
    assert (states.speeds < 0.05).all()
    steps = round(states.sim_time / sim.status().timestep)
    assert steps % round(0.25 / sim.status().timestep) == 0  # stopped at a check


def test_run_until_rest_runs_to_the_end_when_bodies_keep_moving(sim: Client) -> None:
    sim.set_params({"gravity": [0.0, 0.0, 0.0]})
    names, group = ball_row(2)
    sim.spawn(group)
    sim.set_states(names, twists=np.tile([0.5, 0, 0, 0, 0, 0], (2, 1)))
    states, at_rest = sim.run_until_rest(1.0, names, speed=0.05, every=0.25)
    assert not at_rest
    assert states.sim_time == pytest.approx(1.0, abs=sim.status().timestep)


@pytest.mark.parametrize("args", [
    {"until_rest": {"speed": 0.05, "every": 0.25}},  # nothing to read
    {"read": ["ball_0"], "until_rest": {"speed": 0.05}},
    {"read": ["ball_0"], "until_rest": {"speed": -1, "every": 0.25}},
    {"read": ["ball_0"], "until_rest": {"speed": 0.05, "every": 0.25, "when": 1}},
])
def test_a_bad_until_rest_is_rejected_before_any_step(sim: Client, args: dict) -> None:
    ground_and_balls(sim, count=1)
    reply = sim.request("run_until", {"sim_time": 1.0, **args})
    assert reply.code == ResultCode.INVALID_ARGUMENT
    assert "until_rest" in reply.message
    reply = sim.request("step", {"count": 10, **args})  # step has no until_rest at all
    assert reply.code == ResultCode.INVALID_ARGUMENT
    assert "until_rest" in reply.message
    assert sim.status().step == 0
