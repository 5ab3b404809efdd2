"""Which bin each ball ended in, and why the others count as unsettled or lost.

A ball's outcome, first match wins:

* ``nan``: its position or speed is not finite (the engine blew up);
* ``below_floor``: its centre is below the floor's top face (it fell through);
* ``tunnelled``: its centre is inside a solid (pin, divider, funnel, side or back wall,
  glass): a step carried it into the solid faster than contacts could push it out;
* ``outside_cavity``: its centre is beyond a side wall, the glass or the back wall, or
  above the walls' top: it left the board;
* ``settled``: below the dividers' top and slower than ``settle_speed``: counted in a bin;
* ``moving``: still faster than ``settle_speed`` (run longer or raise the cap);
* ``stuck``: at rest above the dividers (lodged on a pin or in the funnel).

The paper's "lost balls" are the physics failures (``LOSS_REASONS``); ``moving`` and
``stuck`` are unsettled but not lost. Only settled balls enter the bin counts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from galton.analysis.board import BoardSpec, BoardSpecError
from galton.analysis.board_geometry import board_primitives, signed_distance
from galton.analysis.board_layout import board_top, cavity_faces, divider_positions, divider_top

OUTCOMES = ("settled", "moving", "stuck", "below_floor", "outside_cavity", "tunnelled", "nan")
LOSS_REASONS = ("below_floor", "outside_cavity", "tunnelled", "nan")
UNSETTLED = ("moving", "stuck")
DEFAULT_SETTLE_SPEED = 0.05  # m/s: well above the ~0.006 m/s jiggle of balls in a pile


@dataclass(frozen=True, eq=False)
class BallOutcomes:
    """Per-ball outcomes and bins (-1 unless settled), bin counts, and counts by reason."""

    outcomes: tuple[str, ...]
    bin_index: np.ndarray
    counts: np.ndarray
    reasons: dict[str, int]

    @property
    def settled(self) -> int:
        return int(self.counts.sum())

    @property
    def lost(self) -> int:
        """Balls lost to physics failures, as the paper counts them."""
        return sum(self.reasons[r] for r in LOSS_REASONS)

    @property
    def unsettled(self) -> int:
        return sum(self.reasons[r] for r in UNSETTLED)


def assign_bins(spec: BoardSpec, positions: np.ndarray, offset_x: float = 0.0) -> np.ndarray:
    """Bin index 0 .. bins - 1 (from -x) of each ball by its x alone; -1 where x is not finite.

    A ball left of the first divider's centre line is in bin 0, and so on; x beyond the
    side walls still maps to the outer bins, so call ``classify_balls`` to know if it counts.
    """
    x = _as_points(positions)[:, 0] - offset_x
    bins = np.searchsorted(np.asarray(divider_positions(spec)), x, side="right")
    return np.where(np.isfinite(x), bins, -1).astype(int)


def classify_balls(spec: BoardSpec, positions: np.ndarray, speeds: np.ndarray,
                   offset_x: float = 0.0,
                   settle_speed: float = DEFAULT_SETTLE_SPEED) -> BallOutcomes:
    """Outcome of every ball from its final centre and speed; board shifted by ``offset_x``."""
    points, speed = _as_points(positions), np.asarray(speeds, dtype=float).reshape(-1)
    if len(speed) != len(points):
        raise BoardSpecError("speeds", f"holds {len(speed)} values for {len(points)} balls")
    outcome = np.full(len(points), "", dtype=object)
    finite = np.isfinite(points).all(axis=1) & np.isfinite(speed)
    _mark(outcome, ~finite, "nan")
    safe = np.where(finite[:, None], points, 0.0)
    _mark(outcome, safe[:, 2] < spec.floor.z, "below_floor")
    _mark(outcome, _inside_solid(spec, safe, offset_x), "tunnelled")
    _mark(outcome, _outside_cavity(spec, safe, offset_x), "outside_cavity")
    slow, in_bins = speed < settle_speed, safe[:, 2] < divider_top(spec)
    _mark(outcome, slow & in_bins, "settled")
    _mark(outcome, slow & ~in_bins, "stuck")
    _mark(outcome, np.ones(len(points), dtype=bool), "moving")
    return _summarise(spec, tuple(outcome), assign_bins(spec, safe, offset_x))


def _as_points(positions: np.ndarray) -> np.ndarray:
    points = np.asarray(positions, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise BoardSpecError("positions", f"must be an (n, 3) array, got shape {points.shape}")
    return points


def _mark(outcome: np.ndarray, where: np.ndarray, label: str) -> None:
    """Give ``label`` to the balls selected by ``where`` that have no outcome yet."""
    outcome[where & (outcome == "")] = label


def _inside_solid(spec: BoardSpec, points: np.ndarray, offset_x: float) -> np.ndarray:
    solids = [p for p in board_primitives(spec, offset_x) if p.role != "floor"]
    if len(points) == 0:
        return np.zeros(0, dtype=bool)
    inside: np.ndarray = np.min([signed_distance(p, points) for p in solids], axis=0) < 0.0
    return inside


def _outside_cavity(spec: BoardSpec, points: np.ndarray, offset_x: float) -> np.ndarray:
    front, back = cavity_faces(spec)
    x, y, z = points[:, 0] - offset_x, points[:, 1], points[:, 2]
    return (np.abs(x) > spec.walls.inner_x) | (y < front) | (y > back) | (z > board_top(spec))


def _summarise(spec: BoardSpec, outcomes: tuple[str, ...], bins: np.ndarray) -> BallOutcomes:
    settled = np.array([o == "settled" for o in outcomes], dtype=bool)
    bin_index = np.where(settled, bins, -1)
    counts = np.bincount(bin_index[settled], minlength=spec.bins)
    reasons = {r: outcomes.count(r) for r in OUTCOMES if r != "settled"}
    return BallOutcomes(outcomes, bin_index, counts, reasons)
