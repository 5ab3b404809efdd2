"""Recording a world's motion and replaying it (galton-client record / view FILE), and the
stream-states command; the page itself is drawn by a browser in test_view_browser.py."""

from __future__ import annotations

import json
import socket
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support.cli import invoke, run, target_of

from galton.client import Client, EmbeddedDaemon, meshes, plane, spheres
from galton.client.sdk.recording import Recorder, Recording, recordings_in
from galton.protocol import InvalidArgumentError

viser = pytest.importorskip("viser", reason="the [view] extra is not installed")

WAIT_S = 20.0


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


def test_a_recording_keeps_every_entity_and_replays_in_the_page(
        mujoco_sim: Client, tmp_path: Path) -> None:
    sim = mujoco_sim
    sim.spawn(plane(), spheres(["early"], [[0.0, 0.0, 1.0]], radius=0.05, tags=["red"]))
    path = tmp_path / "results" / "trial.npz"
    sim.play(rtf=0.5)
    try:
        with Recorder(sim, path, rate=30) as recorder:
            assert recorder.wait_for(3, WAIT_S)
            sim.spawn(spheres(["late"], [[0.3, 0.0, 1.0]], radius=0.05))
            count = len(recorder.samples)
            assert recorder.wait_for(count + 3, WAIT_S)
    finally:
        sim.pause()
    recording = Recording.load(path)
    assert recording.names[:2] == ["ground", "early"] and "late" in recording.names
    assert [info.shape for info in recording.infos][:2] == ["plane", "sphere"]
    assert recording.infos[1].tags == ("red",)
    late = recording.names.index("late")
    assert np.isnan(recording.poses[0, late]).all()  # not there yet: absent, not at 0
    assert not np.isnan(recording.poses[-1]).any()
    assert np.all(np.diff(recording.times) >= 0)
    assert recording.poses[-1, 1, 2] < recording.poses[0, 1, 2]  # it fell
    assert recordings_in(tmp_path) == [path]  # a results directory replays what it holds

    from galton.client.view.replay import ReplayView, visible_poses
    server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        page = ReplayView.open(tmp_path, server, None)
        assert page.drawing.names == tuple(recording.names)
        assert visible_poses(recording.poses[0])[late, 2] < -100  # drawn out of sight
        _seek_while_paused(page, recording)
    finally:
        server.stop()


def _seek_while_paused(page: Any, recording: Recording) -> None:
    """The time slider spans the recording's sim time; paused (the Pause button), moving
    it draws the sample of that time, and Play moves it on again."""
    times = recording.times
    assert (page.time.min, page.time.max) == pytest.approx((times[0], times[-1]))
    page.play(False)
    middle = len(times) // 2
    page.time.value = float(times[middle])
    stop = threading.Event()
    runner = threading.Thread(target=page.run, args=(stop,))
    runner.start()
    try:
        _until(page, lambda: f"frame {middle} of" in page.clock.content and
               "paused" in page.clock.content)
        page.play(True)
        _until(page, lambda: "playing" in page.clock.content)
    finally:
        stop.set()
        runner.join()


def _until(page: Any, done: Any) -> None:
    """Wait on the page's drawings until ``done()``."""
    deadline = time.monotonic() + WAIT_S
    while not done():
        assert page.drew.wait(max(0.0, deadline - time.monotonic())), "nothing drawn"
        page.drew.clear()


PYRAMID = (np.array([[-0.1, -0.1, 0.0], [0.1, -0.1, 0.0], [0.1, 0.1, 0.0], [-0.1, 0.1, 0.0],
                     [0.0, 0.0, 0.2]]),
           np.array([[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]))


CRATE = """<robot name="crate"><link name="base">
  <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
  </inertial><collision><geometry><box size="0.2 0.4 0.6"/></geometry></collision>
</link></robot>"""


def test_a_recording_keeps_mesh_and_link_shapes_and_an_older_one_draws_boxes(
        mujoco_sim: Client, tmp_path: Path) -> None:
    """Shapes told at the start (a mesh, a robot's link), and at save for a mesh spawned
    meanwhile; a recording made before recordings kept shapes still loads, its mesh drawn
    as its box (8 corners)."""
    vertices, faces = PYRAMID
    mujoco_sim.spawn(meshes(["early"], [[0, 0, 0.5]], vertices, faces, static=True))
    [crate] = mujoco_sim.load_model("urdf", text=CRATE, prefix="u_")
    path = tmp_path / "meshes.npz"
    with Recorder(mujoco_sim, path, rate=30) as recorder:
        mujoco_sim.spawn(meshes(["late"], [[1, 0, 0.5]], vertices * 2, faces, static=True))
        mujoco_sim.step(1)  # a sample that holds it
        assert recorder.wait_for(len(recorder.samples) + 2, WAIT_S)
    recording = Recording.load(path)
    assert set(recording.shapes) == {"early", "late", crate}
    np.testing.assert_allclose(recording.shapes["late"][0].vertices, vertices * 2)
    (tmp_path / "old").mkdir()
    with np.load(path) as data:  # as saved before recordings kept shapes
        np.savez(tmp_path / "old" / "meshes.npz", entities=data["entities"],
                 times=data["times"], poses=data["poses"])

    from galton.client.view.replay import ReplayView
    server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        page = ReplayView.open(path, server, None)
        np.testing.assert_allclose(page.drawing.vertices_of("early"), vertices, atol=1e-6)
        np.testing.assert_allclose(page.drawing.vertices_of("late"), vertices * 2, atol=1e-6)
        link = page.drawing.vertices_of(crate)  # its collision box, not a marker cube
        np.testing.assert_allclose(np.ptp(link, axis=0), [0.2, 0.4, 0.6], atol=1e-5)
        old = ReplayView.open(tmp_path / "old", server, None)
        assert Recording.load(tmp_path / "old" / "meshes.npz").shapes == {}
        assert len(old.drawing.vertices_of("early")) == 8
    finally:
        server.stop()


def test_a_recording_starts_where_its_block_finds_the_world(
        mujoco_sim: Client, tmp_path: Path) -> None:
    """Run flat out from the first line of the block, the world is far along before a late
    subscription would see it: the recorder holds the block until its first sample."""
    mujoco_sim.spawn(plane(), spheres(["ball"], [[0.0, 0.0, 1.0]], radius=0.05))
    start = mujoco_sim.status().sim_time
    with Recorder(mujoco_sim, tmp_path / "flat-out.npz", rate=60) as recorder:
        assert len(recorder.samples) >= 1
        mujoco_sim.run_until(start + 20.0)
    recording = Recording.load(tmp_path / "flat-out.npz")
    assert recording.times[0] == pytest.approx(start)
    assert recording.poses[0, recording.names.index("ball"), 2] == pytest.approx(1.0)


def test_a_file_that_is_no_recording_is_refused(tmp_path: Path) -> None:
    bad = tmp_path / "bad.npz"
    bad.write_bytes(b"not a zip")
    with pytest.raises(InvalidArgumentError, match="no recording"):
        Recording.load(bad)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(InvalidArgumentError, match="holds no recording"):
        recordings_in(empty)


def test_stream_states_prints_samples_and_closes_its_stream(
        mujoco_sim: Client, daemons: dict[str, EmbeddedDaemon]) -> None:
    mujoco_sim.spawn(spheres(["a", "b"], [[0, 0, 1], [1, 0, 1]], radius=0.05))
    mujoco_sim.step(10)
    out = run([*target_of(daemons["mujoco"]), "stream-states", "b", "--rate", "20",
               "--count", "2", "--json"])
    assert out.exit_code == 0, out.output
    lines = [json.loads(line) for line in out.stdout.splitlines()]
    assert len(lines) == 2 and lines[0]["names"] == ["b"] and lines[0]["step"] == 10
    assert lines[0]["poses"] == mujoco_sim.get_states(["b"]).poses.tolist()


def test_bench_record_saves_a_recording_per_trial_that_the_page_replays(
        daemons: dict[str, EmbeddedDaemon], tmp_path: Path) -> None:
    from support.daemons import start_daemon

    daemon = start_daemon(daemons, "mujoco")
    out = tmp_path / "run"
    summary = invoke(["bench", "--connect", daemon.endpoint, "--instances", daemon.instance,
                      "--engines", "mujoco", "--board", "small", "--balls", "5",
                      "--repetitions", "2", "--out", str(out), "--record", "--json"])
    assert [e["engine"] for e in summary["engines"]] == ["mujoco"]
    paths = recordings_in(out)
    assert [p.name for p in paths] == ["mujoco_5balls_rep1.npz", "mujoco_5balls_rep2.npz"]
    first_trial_end = json.loads((out / "results.json").read_text())["trials"][0]["sim_time"]
    recording = Recording.load(paths[1])
    balls = [i for i, info in enumerate(recording.infos) if "ball" in info.tags]
    assert len(balls) == 5 and {recording.infos[i].shape for i in balls} == {"sphere"}
    assert len(recording.times) >= 2 and np.all(np.diff(recording.times) >= 0)
    # From its own built board on, not the world the first trial left.
    assert recording.times[0] < min(0.5, first_trial_end / 2)
    assert not np.isnan(recording.poses[-1, balls]).any()  # every ball released by the end
    released = [int(np.argmax(~np.isnan(recording.poses[:, i, 2]))) for i in balls]
    assert all(recording.poses[-1, i, 2] < recording.poses[row, i, 2]  # each one fell
               for i, row in zip(balls, released, strict=True))

    from galton.client.view.replay import ReplayView
    server = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    try:
        page = ReplayView.open(out, server, None)
        assert page.drawing.names == tuple(recording.names)
    finally:
        server.stop()
