"""galton-daemon --snapshot-key: blobs are sealed with a secret, so an edited and re-sealed
blob is refused whatever it says (issue 35, item 3), while the daemon's own blobs, and
those of daemons holding the same key, restore. Engine-independent: MuJoCo only."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from support import snapshot
from support.daemons import start_daemon

from galton.client import Client, EmbeddedDaemon, plane, spheres, wait_for_daemon
from galton.client.fuzz.snapshots import open_blob, reseal
from galton.client.sdk.embedded import daemon_command
from galton.protocol import InvalidArgumentError


def test_a_keyed_daemon_restores_its_own_blobs_and_no_resealed_one(
        tmp_path: Path, daemons: dict[str, EmbeddedDaemon]) -> None:
    key = tmp_path / "snapshot.key"
    key.write_bytes(bytes(range(32)))
    with EmbeddedDaemon("mujoco", instance="test-snapshot-key",
                        extra_args=["--snapshot-key", str(key)]) as daemon, \
            Client(daemon.instance, daemon.endpoint, timeout=20.0) as sim:
        wait_for_daemon(sim.session, daemon.instance, 60.0)
        sim.spawn(plane(), spheres(["a"], [[0, 0, 0.5]], 0.05))
        blob = bytes(sim.call("snapshot", {"blob": True})["blob"])
        sim.step(5)
        sim.call("restore", {"blob": blob})
        assert sim.status().step == 0
        body = open_blob(blob)
        body["entities"][1]["size"] = [0.07]  # consistent in form: only the seal catches it
        before = snapshot(sim)
        with pytest.raises(InvalidArgumentError, match="snapshot-key"):
            sim.call("restore", {"blob": reseal(body)})
        snapshot(sim).assert_same(before)
    unkeyed = start_daemon(daemons, "mujoco")
    with Client(unkeyed.instance, unkeyed.endpoint, timeout=20.0) as other:
        other.load_world("mujoco")
        with pytest.raises(InvalidArgumentError, match="snapshot-key"):
            other.call("restore", {"blob": blob})


def test_a_short_snapshot_key_is_refused_at_start(tmp_path: Path) -> None:
    key = tmp_path / "short.key"
    key.write_bytes(b"short")
    done = subprocess.run([*daemon_command(), "--engine", "mujoco", "--instance",
                           "test-short-key", "--snapshot-key", str(key)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2 and "at least 16" in done.stderr
