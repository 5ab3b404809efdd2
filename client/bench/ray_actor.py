"""The Ray actor of ``bench --ray``: one daemon on its node's loopback, trials through the SDK.

It runs on the cluster's nodes (each needs galton-bridge with its engines and the
``[cluster]`` extra). It exits the moment its daemon dies, or stops answering mid-trial: a
real process death, which Ray sees, so Ray restarts it (a fresh daemon) and reruns the trial
it held. Each start has its own incarnation, by which the driver tells a rerun trial.
"""

from __future__ import annotations

import os
import tempfile
import threading
import uuid
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import ray

from galton.analysis.records import TrialRecord
from galton.client.bench.futures import SnapshotWorlds
from galton.client.bench.picture import Animation, take_pictures
from galton.client.bench.trial import TrialConfig, run_trial
from galton.client.sdk.client import Client
from galton.client.sdk.embedded import EmbeddedDaemon
from galton.client.sdk.values import Prediction
from galton.protocol import DaemonUnreachableError, RequestTimeoutError

# The exit status of an actor whose daemon died (any non-zero status: Ray restarts it).
DAEMON_LOST_EXIT = 75
RECORDING_KEY = "recording"  # the trial's recording among an ActorResult's files
PICTURES_FOLDER = "pictures"  # ... and its pictures, under this folder


@dataclass(frozen=True)
class ActorFacts:
    """What an actor says of itself: its daemon (pid, endpoint, instance), its node, and
    its incarnation (new at each start, so a restart is seen)."""

    name: str
    incarnation: str
    node: str
    daemon_pid: int
    endpoint: str
    host: dict[str, Any]


@dataclass
class ActorResult:
    """A finished trial: its record, the incarnation that ran it, and the files it made
    (pictures, a recording) as bytes, since the actor's node may not be the driver's."""

    record: TrialRecord
    incarnation: str
    files: dict[str, bytes] = field(default_factory=dict)
    taken: dict[str, str] = field(default_factory=dict)


@dataclass
class FutureBatch:
    """A batch of an ensemble's futures, and the incarnation that imagined it."""

    prediction: Prediction
    incarnation: str


class DaemonActor:
    """A Ray actor hosting one daemon on its node's loopback (see the module's docstring)."""

    def __init__(self, name: str, engine: str, timeout: float) -> None:
        self.name = name
        self.incarnation = uuid.uuid4().hex
        self.closing = False
        self.daemon = EmbeddedDaemon(engine, instance=name).start()
        self.client = Client(name, self.daemon.endpoint, timeout=timeout)
        self.snapshots = SnapshotWorlds(self.client)
        threading.Thread(target=self._exit_with_daemon, name="daemon-watch",
                         daemon=True).start()

    def _exit_with_daemon(self) -> None:
        assert self.daemon.process is not None
        self.daemon.process.wait()
        if not self.closing:
            os._exit(DAEMON_LOST_EXIT)

    def facts(self) -> ActorFacts:
        assert self.daemon.process is not None
        return ActorFacts(self.name, self.incarnation, ray.get_runtime_context().get_node_id(),
                          self.daemon.process.pid, self.daemon.endpoint,
                          self.client.capabilities().host)

    def run(self, trial: TrialConfig, pictures: bool, animation: Animation | None
            ) -> ActorResult:
        """One trial (with its pictures, if asked, and its recording, as bytes)."""
        with tempfile.TemporaryDirectory(prefix="galton-ray-") as folder:
            here = Path(folder)
            local = trial if trial.recording is None else replace(
                trial, recording=here / RECORDING_KEY)
            try:
                record = run_trial(self.client, local)
                taken = take_pictures(self.client, trial, here / PICTURES_FOLDER,
                                      animation) if pictures else {}
            except (DaemonUnreachableError, RequestTimeoutError):
                self.daemon.process.kill()  # type: ignore[union-attr]
                os._exit(DAEMON_LOST_EXIT)  # gone or silent: Ray restarts us, reruns it
            record.daemon = self.name
            files = {p.relative_to(here).as_posix(): p.read_bytes()
                     for p in here.rglob("*") if p.is_file()}
        return ActorResult(record, self.incarnation, files, taken)

    def predict(self, digest: str, blob: list[Any], engine: str, args: dict[str, Any]
                ) -> FutureBatch:
        """A batch of futures (``args``: ``Client.predict``'s) from the snapshot ``digest``,
        restored here once: ``blob`` holds its object reference, fetched only then."""
        try:
            world = self.snapshots.world(digest, engine, lambda: bytes(ray.get(blob[0])))
            return FutureBatch(world.predict(**args), self.incarnation)
        except (DaemonUnreachableError, RequestTimeoutError):
            self.daemon.process.kill()  # type: ignore[union-attr]
            os._exit(DAEMON_LOST_EXIT)  # gone or silent: Ray restarts us, reruns it

    def close(self) -> None:
        self.closing = True
        self.client.close()
        self.daemon.stop()
