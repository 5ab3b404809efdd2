"""The paper's trigger, closed into a loop: "prediction failures will serve as triggers to
improve the models". A ``SurpriseWatch`` sits on the compare (mirroring) path: it keeps
what was observed, and when the anomaly score stays above ``threshold`` for ``window``
comparisons in a row it says so, with the observation to calibrate on. The daemon keeps
the same streak itself with compare's ``trigger`` (``sim.compare(..., trigger=(3.0, 4))``:
the reply's ``suggested`` and a ``calibration_suggested`` event for every listener); the
watch then only keeps the episode (examples/learn_from_surprise.py).

>>> watch = SurpriseWatch(threshold=3.0, window=4)
>>> watch.start(sim.status().sim_time, ["box"], seen_poses)  # a new episode: its start
>>> score = sim.compare(["box"], seen_poses).score
>>> if watch.observe(sim.status().sim_time, seen_poses, score):   # surprised for a while
...     fit = sim.calibrate({"box.friction": (0.05, 1.5)}, *watch.observed(), apply=True)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from galton.protocol import InvalidArgumentError


@dataclass
class SurpriseWatch:
    """Anomaly scores in a row above ``threshold``; ``window`` of them is a surprise."""

    threshold: float = 3.0
    window: int = 5
    streak: int = 0
    names: list[str] = field(default_factory=list)
    times: list[float] = field(default_factory=list)
    poses: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        if self.window < 1 or not self.threshold > 0:
            raise InvalidArgumentError("a surprise watch needs a window >= 1 and a threshold "
                                       "> 0")

    def start(self, sim_time: float, names: Sequence[str], poses: ArrayLike) -> None:
        """Begin an episode at this observation (the start a calibration predicts from)."""
        self.names, self.times, self.poses = list(names), [], []
        self.streak = 0
        self._keep(sim_time, poses)

    def observe(self, sim_time: float, poses: ArrayLike, score: float) -> bool:
        """Keep this observation; True once ``window`` scores in a row were surprising."""
        self._keep(sim_time, poses)
        self.streak = self.streak + 1 if score > self.threshold else 0
        return self.streak >= self.window

    def observed(self) -> tuple[list[str], np.ndarray, np.ndarray]:
        """The episode's names, times and poses: ``sim.calibrate(fit, *watch.observed())``."""
        return self.names, np.array(self.times), np.array(self.poses)

    def _keep(self, sim_time: float, poses: ArrayLike) -> None:
        rows = np.asarray(poses, float).reshape(len(self.names), 7)
        self.times.append(float(sim_time))
        self.poses.append(rows.copy())
