"""A recording of a world's motion: the entities as ``list`` described them (with the shapes
of loaded models' bodies and spawned meshes, as ``get_shapes`` told them), and their poses
at each sample of a state stream, saved as one ``.npz`` file that ``galton-client view
FILE`` (or a directory of them) replays.

>>> with Recorder(sim, Path("results/trial.npz"), rate=60):
...     run_trial(sim, config)          # the bench's trial, unchanged

Entities that come and go during the recording (balls released one by one) are recorded
with a NaN pose while absent, so that every sample has the same rows.
"""

from __future__ import annotations

import json
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.client.sdk import drawn_shapes
from galton.client.sdk.drawn_shapes import Shapes
from galton.client.sdk.streams import StateSample
from galton.protocol import POSE_WIDTH, EntityInfo, GaltonError, InvalidArgumentError

if TYPE_CHECKING:
    from galton.client.sdk.client import Client
    from galton.client.sdk.streams import StateStream

SUFFIX = ".npz"  # galton.client.cli.view.RECORDING_SUFFIX
# How long a recorder waits for its stream's first sample before its block runs: samples
# come every 1/rate s of wall time; a faulted world publishes none, and is recorded from
# its first sample after it recovers.
FIRST_SAMPLE_WAIT_S = 5.0


@dataclass
class Recording:
    """Entities, sample times and poses (samples, entities, 7; NaN where absent), and the
    shapes of those drawn by them (none in a recording made before they were kept)."""

    infos: list[EntityInfo]
    times: np.ndarray
    poses: np.ndarray
    shapes: Shapes = field(default_factory=dict)

    @property
    def names(self) -> list[str]:
        return [info.name for info in self.infos]

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        entities = json.dumps([info.to_wire() for info in self.infos])
        with path.open("wb") as out:
            arrays: dict[str, Any] = {"entities": np.asarray(entities), "times": self.times,
                                      "poses": self.poses,
                                      **drawn_shapes.pack_shapes(self.shapes)}
            np.savez_compressed(out, **arrays)

    @classmethod
    def load(cls, path: Path) -> Recording:
        try:
            with np.load(path, allow_pickle=False) as data:
                infos = [EntityInfo.from_wire(row) for row in json.loads(str(data["entities"]))]
                times, poses = np.asarray(data["times"]), np.asarray(data["poses"])
                shapes = drawn_shapes.unpack_shapes(data)
        except (OSError, ValueError, KeyError, GaltonError) as error:
            raise InvalidArgumentError(f"{path} is no recording of galton-client: {error}") \
                from error
        if poses.ndim != 3 or poses.shape[1:] != (len(infos), POSE_WIDTH) \
                or len(times) != len(poses):
            raise InvalidArgumentError(f"{path}: its poses do not match its entities and times")
        return cls(infos, times, poses, shapes)


def recordings_in(source: Path) -> list[Path]:
    """The recording a path names, or every recording in a directory (a bench's results)."""
    if source.is_dir():
        found = sorted(source.rglob(f"*{SUFFIX}"))
        if not found:
            raise InvalidArgumentError(
                f"{source} holds no recording (*{SUFFIX}): record a trial with "
                "`galton-client record FILE` while it runs")
        return found
    if not source.is_file():
        raise InvalidArgumentError(f"{source}: no such file or directory")
    return [source]


class Recorder:
    """Records a state stream of ``client``'s world until the block ends, then saves it."""

    def __init__(self, client: Client, path: Path, rate: float = 60.0) -> None:
        self.client = client
        self.path = path
        self.rate = rate
        self.samples: list[StateSample] = []
        self.shapes: Shapes = {}
        self._lock = threading.Condition()
        self._stream: StateStream | None = None

    def _take(self, sample: StateSample) -> None:
        if sample.ended is None:
            with self._lock:
                self.samples.append(sample)
                self._lock.notify_all()

    def wait_for(self, count: int, timeout: float) -> bool:
        """Wait until ``count`` samples are recorded (False if ``timeout`` s pass first)."""
        with self._lock:
            return self._lock.wait_for(lambda: len(self.samples) >= count, timeout)

    def __enter__(self) -> Recorder:
        """Open the stream and wait for its first sample, so the recording starts with the
        world as the block finds it (a world run flat out inside the block may otherwise
        be far along before the subscription sees its first sample)."""
        self.shapes = drawn_shapes.shapes_for_drawing(self.client, self.client.list())
        self._stream = self.client.stream_states(rate=self.rate, callback=self._take)
        self.wait_for(1, FIRST_SAMPLE_WAIT_S)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._stream is not None:
            self._stream.close()
        self.recording().save(self.path)

    def recording(self) -> Recording:
        """What was recorded, entities as ``list`` describes them now (or as a name alone
        when gone since); shapes as told at the start, those of entities that came since
        asked now."""
        with self._lock:
            samples = list(self.samples)
        order: dict[str, int] = {}
        for sample in samples:
            for name in sample.names:
                order.setdefault(name, len(order))
        poses = np.full((len(samples), len(order), POSE_WIDTH), np.nan)
        for row, sample in enumerate(samples):
            poses[row, [order[name] for name in sample.names]] = sample.poses
        listed = {info.name: info for info in self.client.list()}
        infos = [listed.get(name, EntityInfo(name, "link")) for name in order]
        times = np.asarray([sample.sim_time for sample in samples], dtype=float)
        came = [info for info in infos if info.name in listed and info.name not in self.shapes]
        shapes = {**self.shapes, **drawn_shapes.shapes_for_drawing(self.client, came)}
        return Recording(infos, times, poses, {n: shapes[n] for n in order if n in shapes})
