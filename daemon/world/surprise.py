"""compare's surprise trigger (the paper's "prediction failures will serve as triggers to
improve the models"): a world counts its comparisons in a row whose anomaly score passed
the trigger's threshold; when the count reaches the trigger's window, once per streak,
the comparison suggests a calibration (a ``calibration_suggested`` event). A trigger that
starts the calibration itself (its ``calibrate``) has the streak keep its observations:
the episode the daemon fits to (daemon/core/surprise_calibration.py)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class Sample:
    """One surprising comparison's observation: when, which bodies, their poses (twists)."""

    sim_time: float
    names: tuple[str, ...]
    poses: np.ndarray
    twists: np.ndarray | None = None


@dataclass
class SurpriseStreak:
    """Surprising comparisons in a row, and the sim time the streak began."""

    count: int = 0
    since: float = math.nan
    samples: list[Sample] = field(default_factory=list)  # kept where a trigger asks

    def observe(self, score: float, threshold: float, window: int, sim_time: float,
                sample: Sample | None = None) -> bool:
        """Count this comparison (keeping ``sample``, of the same bodies as the ones kept);
        True on the one that makes the streak ``window`` long."""
        if score > threshold:
            if self.count == 0:
                self.since = sim_time
            self.count += 1
            if sample is not None:
                if self.samples and self.samples[0].names != sample.names:
                    self.samples.clear()  # an episode is of one set of bodies
                self.samples.append(sample)
                del self.samples[:-window]  # the streak's last window, no more
        else:
            self.clear()
        return self.count == window

    def clear(self) -> None:
        self.count, self.since = 0, math.nan
        self.samples.clear()
