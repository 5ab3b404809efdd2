"""compare's surprise trigger (the paper's "prediction failures will serve as triggers to
improve the models"): a world counts its comparisons in a row whose anomaly score passed
the trigger's threshold; when the count reaches the trigger's window, once per streak,
the comparison suggests a calibration (a ``calibration_suggested`` event)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class SurpriseStreak:
    """Surprising comparisons in a row, and the sim time the streak began."""

    count: int = 0
    since: float = math.nan

    def observe(self, score: float, threshold: float, window: int, sim_time: float) -> bool:
        """Count this comparison; True on the one that makes the streak ``window`` long."""
        if score > threshold:
            if self.count == 0:
                self.since = sim_time
            self.count += 1
        else:
            self.clear()
        return self.count == window

    def clear(self) -> None:
        self.count, self.since = 0, math.nan
