"""Follow balls down the board, row by row: are their left/right choices fair and independent?

Usage: python research/walk_probe.py ENGINE [--balls 500] [--seed 0] [--params JSON]
                                    [--crowd stream|all-at-once] [--board NAME_OR_TOML]

A binomial board needs each ball to make one fair, independent left/right choice per row.
The 500-ball runs come out flatter than the binomial (``research/seed_spread.py``: like
6-7 independent rows, not 11). This probe looks at the walk itself. It builds the ``paper``
board (or ``--board``: a preset name or a TOML/JSON file, e.g. ``research/boards/*.toml``)
in-process (the bench's world, repetition 0 of ``--seed``). Without ``--crowd`` it
drops the stream release's balls one at a time, each alone on the board (no ball-ball
contact, no piles); with ``--crowd MODE`` it releases them as the bench does in that mode.
It steps one step at a time and notes, for every ball, its x each time it goes down
through a pin row's axis, and its bin (from x once its centre is below the dividers' top,
as ``assign_bins`` reads it).

Reading the walk. A row with an odd pin count has a pin at x = 0, an even count has pins
at +-pitch / 2, so at a row's axis a ball is in a gap at an odd (or even) multiple of half
a pitch. Each crossing is rounded to the nearest gap of the row's parity: the gaps beside
the walls of the short rows (8, 9, 10 pins) are wider than half a pitch, and plain rounding
read some as a pin's position (moves of 0 and 2). A ball that bounces back up through a row
and comes down in another gap counts by its last crossing (``changed_gap`` says how often
the first one differed), so the 11 moves (+-1 half-pitch for a deflection by the next pin,
+-3 for a skipped pin) sum to the last row's gap, which is the bin's centre line;
``walk_bin_mismatch`` counts the balls whose bin disagrees.

It prints one JSON line: move sizes; the chance a ball keeps its last direction (0.5 for
independent fair choices), overall and per pair of rows; each row's share of moves to +x;
how often the first move follows the side of the top pin the ball was released on; the
correlation of moves 1, 2 and 3 rows apart; the spread of the ball's position after each
row, in bins (the binomial's is sqrt(r) / 2 after r rows); the bins' width (the binomial's:
1.658) and excess kurtosis (-2 / 11 = -0.18), with the 95 % kurtosis range of a binomial
board with as many balls, and the counts; and two references made from the same walks
(``_references``): the rows made independent, and the top two rows made fair.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from typing import Any

import numpy as np

from galton.analysis import shape
from galton.analysis.board import BoardSpec
from galton.analysis.board_layout import divider_top, pins_per_row, row_heights
from galton.analysis.board_release import Perturbation, perturbation
from galton.analysis.board_scoring import assign_bins
from galton.client.bench.build import ball_group, board_groups
from galton.daemon.engines import create_engine
from galton.daemon.world.world import World
from galton.protocol import BodyGroup

MAX_FALL_S = 20.0  # a lone ball reaches its bin in about 2.5 s; one caught longer is reported
SHUFFLES = 200  # shuffled walks pooled for the independent-rows reference
SHUFFLE_SEED = 0


def build(engine: str, balls: int, seed: int, params: dict[str, Any],
          mode: str = "stream", source: str = "paper") -> tuple[World, BoardSpec, Perturbation]:
    """The bench's world for repetition 0 of ``seed`` on board ``source`` (a preset name or
    a file, as ``BoardSpec.load`` reads it): board built, no balls yet."""
    board = released(source, balls, mode)
    world = World(create_engine(engine))
    contacts = board.contacts.get(engine)
    merged = {**(dict(contacts.params) if contacts else {}), **params}
    if merged:  # as the bench's load_world: no set_params call without parameters
        world.engine.set_params(merged)
    shake = perturbation(board, 0, seed, balls)
    world.spawn(_wire(board_groups(board, engine, shake.board_offset_x)))
    return world, board, shake


def released(source: str, balls: int, mode: str = "stream") -> BoardSpec:
    """Board ``source`` (a preset name or a file) releasing ``balls`` balls in ``mode``."""
    board = BoardSpec.load(source)
    board = board.replace(release=dataclasses.replace(board.release, mode=mode))
    return board.replace(ball=dataclasses.replace(board.ball, count=balls))


def _wire(groups: list[BodyGroup]) -> list[BodyGroup]:
    """As the daemon receives them, so the probe's world is the bench's world."""
    return [BodyGroup.from_wire(g.to_wire()) for g in groups]


class Crossings:
    """Each ball's x (board frame) at its first and last downward crossing of each row's axis,
    and its bin, read once its centre is below the dividers' top (it cannot leave a bin)."""

    def __init__(self, board: BoardSpec, shake: Perturbation, count: int) -> None:
        self.board, self.offset = board, shake.board_offset_x
        self.heights = np.asarray(row_heights(board))
        self.bin_z = divider_top(board) - board.ball.radius
        self.first = np.full((count, board.rows), np.nan)
        self.last = np.full((count, board.rows), np.nan)
        self.bins = np.full(count, -1)
        self.z = np.full(count, np.inf)  # each ball's z at the previous look

    def update(self, index: np.ndarray, poses: np.ndarray) -> None:
        """Note these balls' crossings since the previous look (at most one row per step)."""
        x, z = poses[:, 0] - self.offset, poses[:, 2]
        crossed = (self.z[index, None] >= self.heights) & (z[:, None] < self.heights)
        balls, rows = np.nonzero(crossed)
        who = index[balls]
        self.last[who, rows] = x[balls]
        fresh = np.isnan(self.first[who, rows])
        self.first[who[fresh], rows[fresh]] = x[balls][fresh]
        self.z[index] = z
        landed = (z < self.bin_z) & (self.bins[index] < 0)
        self.bins[index[landed]] = assign_bins(self.board, poses[landed, :3], self.offset)

    def landed(self, index: np.ndarray) -> np.ndarray:
        return self.bins[index] >= 0


def follow_lone(world: World, board: BoardSpec, shake: Perturbation) -> Crossings:
    """Each stream ball alone on the board, from its own release point, down to its bin."""
    count = len(shake.release.times)
    seen = Crossings(board, shake, count)
    for index in range(count):
        name = f"probe_{index:04d}"
        world.spawn(_wire([ball_group(board, world.engine.name, [name],
                                      shake.release.positions[index:index + 1])]))
        one = np.array([index])
        for _ in range(int(MAX_FALL_S / world.engine.timestep)):
            world.step(1)
            seen.update(one, world.get_states([name])[0])
            if seen.landed(one)[0]:
                break
        world.delete([name])
    return seen


def follow_crowd(world: World, board: BoardSpec, shake: Perturbation) -> Crossings:
    """Every ball released as the bench does (each spawned at its release time), followed
    one step at a time until every ball is in a bin or ``MAX_FALL_S`` after the last one."""
    times, positions = shake.release.times, shake.release.positions
    count = len(times)
    seen = Crossings(board, shake, count)
    names = [f"probe_{i:04d}" for i in range(count)]
    active = np.zeros(0, dtype=int)
    released = 0
    for _ in range(int((times[-1] + MAX_FALL_S) / world.engine.timestep)):
        ready = int(np.searchsorted(times, world.sim_time + 1e-9, side="right"))
        if ready > released:
            world.spawn(_wire([ball_group(board, world.engine.name, names[released:ready],
                                          positions[released:ready])]))
            active = np.concatenate([active, np.arange(released, ready)])
            released = ready
        world.step(1)
        if len(active):
            seen.update(active, world.get_states([names[i] for i in active])[0])
            active = active[~seen.landed(active)]
        if released == count and not len(active):
            break
    return seen


def gaps(x: np.ndarray, board: BoardSpec) -> np.ndarray:
    """Crossing x (balls, rows) as gap positions in half-pitches, rounded to each row's parity
    (odd where the row has a pin at x = 0): the lattice's gaps, also beside the walls."""
    half = board.pins.pitch / 2
    parity = np.array([count % 2 for count in pins_per_row(board)])
    return (2 * np.round((x / half - parity) / 2) + parity).astype(int)


def moves(gap: np.ndarray) -> np.ndarray:
    """Each row's move in half-pitches from the top pin at x = 0 (+-1 for a fair walk)."""
    return np.diff(np.concatenate([np.zeros((len(gap), 1), dtype=int), gap], axis=1), axis=1)


def _keeps(steps: np.ndarray) -> np.ndarray:
    """Whether each move (after the first) has the sign of the one before: (balls, rows - 1)."""
    signs = np.sign(steps)
    return signs[:, 1:] == signs[:, :-1]


def _table(bins: np.ndarray, rows: int) -> dict[str, Any]:
    """Width and flatness of these bins, with the binomial's 95 % kurtosis range at this size."""
    counts = np.bincount(bins, minlength=rows + 1)
    flat = shape.flatness(counts, rows)
    return {"width": round(float(bins.std()), 3),
            "excess_kurtosis": round(flat.excess_kurtosis, 3),
            "binomial_range": [round(flat.null_low, 2), round(flat.null_high, 2)],
            "counts": counts.tolist()}


def _law(sums: np.ndarray, rows: int) -> dict[str, float]:
    """Width and excess kurtosis of the bins these walks' sums (half-pitches) end in."""
    bins = np.clip((sums + rows) // 2, 0, rows)
    counts = np.bincount(bins, minlength=rows + 1)
    return {"width": round(float(bins.std()), 3),
            "excess_kurtosis": round(shape.excess_kurtosis(counts, rows), 3)}


def _references(steps: np.ndarray, rows: int) -> dict[str, dict[str, float]]:
    """What the bins would be if part of the walk were independent, pooled over SHUFFLES:
    ``independent_rows`` permutes each row's moves between balls (every row keeps its own law:
    bias, skips, edge effects; the rows become independent); ``fair_top_pair`` replaces the
    first two rows' moves by fair independent +-1 and keeps the rest of each walk."""
    rng = np.random.default_rng(SHUFFLE_SEED)
    shuffled = [rng.permuted(steps, axis=0).sum(axis=1) for _ in range(SHUFFLES)]
    rest = steps[:, 2:].sum(axis=1)
    fair = [rest + rng.choice([-1, 1], size=(len(steps), 2)).sum(axis=1)
            for _ in range(SHUFFLES)]
    return {"independent_rows": _law(np.concatenate(shuffled), rows),
            "fair_top_pair": _law(np.concatenate(fair), rows)}


def _lag_correlations(steps: np.ndarray, lags: int = 3) -> list[float]:
    """Correlation of each move with the one ``lag`` rows below, pooled over rows."""
    return [round(float(np.corrcoef(steps[:, :-k].ravel(), steps[:, k:].ravel())[0, 1]), 3)
            for k in range(1, lags + 1)]


def summarise(seen: Crossings, board: BoardSpec, shake: Perturbation) -> dict[str, Any]:
    """The walks of the balls that crossed every row and landed, and their bins.

    ``first_move_follows_release`` is the share of balls whose first move goes to the side
    of the top pin's axis they were released on: the top pin splits them by that side, so
    the board shift, which moves the pin and not the stream's drop point, biases row 1.
    """
    rows = board.rows
    release_x = shake.release.positions[:, 0] - shake.board_offset_x
    done = ~np.isnan(seen.last).any(axis=1) & (seen.bins >= 0)
    gap = gaps(seen.last[done], board)
    steps = moves(gap)
    walk_bins = np.clip((gap[:, -1] + rows) // 2, 0, rows)
    keeps = _keeps(steps)
    sizes, times = np.unique(np.abs(steps), return_counts=True)
    return {
        "balls": int(done.sum()), "caught": int((~done).sum()),
        "moves": {int(s): int(t) for s, t in zip(sizes, times, strict=True)},
        "keeps_direction": round(float(keeps.mean()), 3),
        "keeps_by_row": np.round(keeps.mean(axis=0), 2).tolist(),
        "right_by_row": np.round((steps > 0).mean(axis=0), 2).tolist(),
        "first_move_follows_release": round(float(
            (np.sign(steps[:, 0]) == np.sign(release_x[done])).mean()), 3),
        "lag_correlations": _lag_correlations(steps),
        "width_by_row": np.round(gap.std(axis=0) / 2, 2).tolist(),
        "changed_gap": int((gaps(seen.first[done], board) != gap).sum()),
        "walk_bin_mismatch": int((walk_bins != seen.bins[done]).sum()),
        "bins": _table(seen.bins[done], rows),
        **_references(steps, rows)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("engine")
    parser.add_argument("--balls", type=int, default=500)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--params", default="{}")
    parser.add_argument("--crowd", choices=["stream", "all-at-once"])
    parser.add_argument("--board", default="paper",
                        help="a preset name or a board TOML/JSON file (default: paper)")
    args = parser.parse_args()
    params = json.loads(args.params)
    world, board, shake = build(args.engine, args.balls, args.seed, params,
                                args.crowd or "stream", args.board)
    seen = (follow_crowd if args.crowd else follow_lone)(world, board, shake)
    world.engine.close()
    print(json.dumps({"engine": args.engine, "board": board.name, "seed": args.seed,
                      "params": params, "crowd": args.crowd,
                      **summarise(seen, board, shake)}))


if __name__ == "__main__":
    main()
