"""Where and when balls enter the board, and the small changes made between repetitions.

"all-at-once" (the paper's release): every ball starts at t = 0 in a cloud above the funnel.
The cloud is a grid of cells of side 2 r + 2 jitter + gap; each ball sits at its cell's
centre plus a uniform jitter of at most ``perturbation.ball_jitter`` per axis, so two
balls are always at least ``release.gap`` apart. Cells fill from the lowest (resting in the
funnel's V) upwards and, within a layer, from the axis outwards; a cell is used only if its
ball, wherever the jitter and the board shift put it, stays ``release.gap`` clear of every
solid.

"stream": ball i starts at t = i * ``release.interval`` from just above the funnel's
opening (``release.stream_height`` above its tip), jittered the same way.

``perturbation(spec, repetition, seed)`` draws one repetition's board shift (normal,
clipped to 3 std) and ball jitter from a seed sequence of (seed, repetition), so every
repetition is reproducible and differs from the others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from galton.analysis.board import BoardSpec, BoardSpecError
from galton.analysis.board_geometry import board_primitives, signed_distance
from galton.analysis.board_layout import board_top, cavity_faces

SHIFT_CLIP = 3.0  # board shifts are clipped to this many standard deviations


@dataclass(frozen=True, eq=False)
class ReleaseSchedule:
    """Start positions (n, 3) in the world frame and release times (n,) in sim seconds."""

    mode: str
    positions: np.ndarray
    times: np.ndarray

    def __len__(self) -> int:
        return len(self.positions)


@dataclass(frozen=True, eq=False)
class Perturbation:
    """One repetition's initial conditions: board shift along x and the balls' jitter."""

    repetition: int
    seed: int
    board_offset_x: float
    ball_jitter: np.ndarray
    release: ReleaseSchedule


def as_generator(rng: np.random.Generator | int) -> np.random.Generator:
    """Accept a Generator or an integer seed; never the global random state."""
    if isinstance(rng, np.random.Generator):
        return rng
    if isinstance(rng, bool) or not isinstance(rng, int | np.integer) or rng < 0:
        raise BoardSpecError("seed", f"must be a non-negative integer or a numpy Generator, "
                             f"got {rng!r}")
    return np.random.default_rng(int(rng))


def max_board_shift(spec: BoardSpec) -> float:
    return SHIFT_CLIP * spec.perturbation.board_shift_std


def _clearance(spec: BoardSpec) -> float:
    """How far a cell's centre must stay from any solid, jitter and board shift included."""
    jitter = spec.perturbation.ball_jitter * math.sqrt(3)
    return spec.ball.radius + jitter + spec.release.gap + max_board_shift(spec)


def _axis(low: float, high: float, step: float) -> np.ndarray:
    """Evenly spaced centres, ``step`` apart, centred in [low, high]; empty if none fit."""
    if high < low:
        return np.empty(0)
    count = math.floor((high - low) / step + 1e-9) + 1
    return (low + high) / 2 + (np.arange(count) - (count - 1) / 2) * step


def cloud_slots(spec: BoardSpec) -> np.ndarray:
    """Nominal ball centres (m, 3) of the all-at-once cloud, in the order they are filled."""
    reach = _clearance(spec)
    cell = 2 * spec.ball.radius + 2 * spec.perturbation.ball_jitter + spec.release.gap
    front, back = cavity_faces(spec)
    xs = _axis(-spec.walls.inner_x + reach, spec.walls.inner_x - reach, cell)
    ys = _axis(front + reach, back - reach, cell)
    z_low = spec.funnel.tip_z + reach
    zs = z_low + np.arange(max(0, int((board_top(spec) - reach - z_low) // cell) + 1)) * cell
    grid = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), axis=-1).reshape(-1, 3)
    if len(grid) == 0:
        return grid
    clear = np.min([signed_distance(p, grid) for p in board_primitives(spec)], axis=0)
    slots = grid[(clear >= reach) & _above_funnel(spec, grid)]
    order = np.lexsort((slots[:, 1], slots[:, 0], np.abs(slots[:, 1] - spec.cavity.centre_y),
                        np.abs(slots[:, 0]), np.round(slots[:, 2], 9)))
    ordered: np.ndarray = slots[order]
    return ordered


def _above_funnel(spec: BoardSpec, points: np.ndarray) -> np.ndarray:
    """Whether each point is above the funnel's upper surface (inside the V, not under it)."""
    f = spec.funnel
    run = np.maximum(np.abs(points[:, 0]) - f.opening / 2, 0.0)
    above: np.ndarray = points[:, 2] > f.tip_z + run * math.tan(math.radians(f.angle_deg))
    return above


def cloud_capacity(spec: BoardSpec) -> int:
    """How many balls the all-at-once cloud can hold."""
    return len(cloud_slots(spec))


def nominal_positions(spec: BoardSpec, count: int | None = None) -> np.ndarray:
    """Unjittered start positions (n, 3) for the spec's release mode."""
    count = _count(spec, count)
    if spec.release.mode == "stream":
        drop = (0.0, spec.cavity.centre_y, spec.funnel.tip_z + spec.release.stream_height)
        return np.tile(drop, (count, 1))
    slots = cloud_slots(spec)
    if count > len(slots):
        raise BoardSpecError("ball.count", (
            f"{count} balls do not fit above the funnel; at most {len(slots)} do (raise "
            "walls.height, or lower perturbation.ball_jitter or release.gap)"))
    return slots[:count]


def release_schedule(spec: BoardSpec, rng: np.random.Generator | int,
                     count: int | None = None) -> ReleaseSchedule:
    """Jittered start positions and release times for ``count`` balls (spec's by default)."""
    return _jittered(spec, nominal_positions(spec, count), as_generator(rng))


def _jittered(spec: BoardSpec, nominal: np.ndarray, rng: np.random.Generator) -> ReleaseSchedule:
    jitter = spec.perturbation.ball_jitter
    positions = nominal + rng.uniform(-jitter, jitter, size=nominal.shape)
    if spec.release.mode == "stream":
        times = np.arange(len(nominal)) * spec.release.interval
    else:
        times = np.zeros(len(nominal))
    return ReleaseSchedule(spec.release.mode, positions, times)


def ball_start_positions(spec: BoardSpec, rng: np.random.Generator | int,
                         count: int | None = None) -> np.ndarray:
    """Start positions (n, 3): the all-at-once cloud, or the stream's drop point, jittered."""
    return release_schedule(spec, rng, count).positions


def perturbation(spec: BoardSpec, repetition: int, seed: int | None = None,
                 count: int | None = None) -> Perturbation:
    """Repetition ``repetition``'s board shift and ball start positions; same inputs, same draw."""
    seed = spec.seed if seed is None else seed
    for where, value in (("repetition", repetition), ("seed", seed)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            raise BoardSpecError(where, f"must be a non-negative integer, got {value!r}")
    board_rng, ball_rng = (np.random.default_rng(s)
                           for s in np.random.SeedSequence([seed, repetition]).spawn(2))
    shift = board_rng.normal(0.0, spec.perturbation.board_shift_std)
    offset = float(np.clip(shift, -max_board_shift(spec), max_board_shift(spec)))
    nominal = nominal_positions(spec, count)
    release = _jittered(spec, nominal, ball_rng)
    return Perturbation(repetition, seed, offset, release.positions - nominal, release)


def _count(spec: BoardSpec, count: int | None) -> int:
    count = spec.ball.count if count is None else count
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise BoardSpecError("count", f"must be a positive integer, got {count!r}")
    return count
