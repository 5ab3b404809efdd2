"""galton-daemon --state-dir: a stopped (SIGTERM) daemon comes back with its world, a
checkpoint that cannot be restored is set aside and the daemon starts empty."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from galton.client import Client, EmbeddedDaemon, plane, spheres

ENGINES = ("mujoco", "pybullet")


def daemon_with(state_dir: Path, engine: str) -> EmbeddedDaemon:
    return EmbeddedDaemon(engine, instance=f"checkpointed-{engine}",
                          extra_args=["--state-dir", str(state_dir)])


@pytest.mark.parametrize("engine", ENGINES)
def test_a_restarted_daemon_comes_back_with_its_world(tmp_path: Path, engine: str) -> None:
    first = daemon_with(tmp_path, engine).start()
    try:
        with Client(first.instance, first.endpoint, timeout=20.0) as sim:
            sim.spawn(plane(), spheres(["a", "b"], [[0, 0, 1], [0.3, 0, 2]], 0.05))
            sim.step(150)
            before = sim.get_states(["a", "b"])
            sim.step(50)
            after_50 = sim.get_states(["a", "b"])
    finally:
        assert first.stop() == 0  # SIGTERM: the daemon saves its world, then exits
    assert (tmp_path / f"{first.instance}.snapshot").is_file()
    with daemon_with(tmp_path, engine).start() as second, \
            Client(second.instance, second.endpoint, timeout=20.0) as sim:
        assert sorted(e.name for e in sim.list()) == ["a", "b", "ground"]
        assert sim.status().step == 200
        np.testing.assert_array_equal(sim.get_states(["a", "b"]).poses, after_50.poses)
        assert not np.array_equal(after_50.poses, before.poses)


def test_a_checkpoint_that_cannot_be_restored_is_set_aside(tmp_path: Path) -> None:
    path = tmp_path / "checkpointed-mujoco.snapshot"
    path.write_bytes(b"not a snapshot")
    with daemon_with(tmp_path, "mujoco").start() as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
        assert sim.list() == []
        assert (tmp_path / "checkpointed-mujoco.snapshot.bad").read_bytes() == b"not a snapshot"
