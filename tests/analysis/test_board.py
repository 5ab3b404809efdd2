"""The board spec, its presets, its primitives, the ball release and the scoring geometry."""

from __future__ import annotations

import dataclasses
import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from galton.analysis.board import (
    PRESETS,
    BoardSpec,
    BoardSpecError,
    EngineContacts,
    PinSpec,
    SurfaceSpec,
    paper_board,
)
from galton.analysis.board_geometry import Primitive, board_primitives, signed_distance
from galton.analysis.board_layout import (
    bin_widths,
    cavity_faces,
    divider_positions,
    funnel_lowest_z,
    pin_centres,
    pins_per_row,
    row_heights,
)
from galton.analysis.board_release import (
    ball_start_positions,
    cloud_capacity,
    perturbation,
    release_schedule,
)
from galton.analysis.board_scoring import LOSS_REASONS, assign_bins, classify_balls
from galton.analysis.errors import AnalysisError

BOARDS_DIR = Path(__file__).resolve().parents[2] / "client" / "boards"
SEED = 20_240_601
TOUCH = 1e-9  # solids may touch along a face; deeper than this is an overlap
ALLOWED_OVERLAPS = {("funnel_left", "wall_left"), ("funnel_right", "wall_right")}


@pytest.fixture(params=sorted(PRESETS))
def board(request: pytest.FixtureRequest) -> BoardSpec:
    return BoardSpec.load(request.param)


# --- spec, presets, serialisation ----------------------------------------------------------


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_toml_preset_equals_python_preset(name: str) -> None:
    assert BoardSpec.from_toml(BOARDS_DIR / f"{name}.toml") == PRESETS[name]()
    assert BoardSpec.load(BOARDS_DIR / f"{name}.toml") == BoardSpec.load(name)


def test_round_trips_through_dict_and_json(board: BoardSpec) -> None:
    calibrated = board.replace(contacts={
        "mujoco": EngineContacts(params={"mujoco.solref": [0.02, 0.3]},
                                 bodies={"ball": SurfaceSpec(friction=0.3)}),
        "pybullet": EngineContacts(bodies={"pin": SurfaceSpec(0.55, 0.85)}),
    })
    for spec in (board, calibrated):
        assert BoardSpec.from_dict(spec.to_dict()) == spec
        assert BoardSpec.from_json(spec.to_json()) == spec


def test_load_rejects_unknown_names_with_a_suggestion() -> None:
    with pytest.raises(BoardSpecError, match="did you mean 'paper'"):
        BoardSpec.load("papr")


def _with(path: str, value: object) -> dict:
    """The paper board's dict with the dotted ``path`` set to ``value``."""
    data = paper_board().to_dict()
    *parents, leaf = path.split(".")
    node = data
    for key in parents:
        node = node.setdefault(key, {})
    node[leaf] = value
    return data


@pytest.mark.parametrize(("path", "value", "field", "hint"), [
    ("bins", 11, "bins", "rows + 1 = 12"),
    ("rows", 2.5, "rows", "integer"),
    ("pins.radius", -0.1, "pins.radius", "(0.0, inf]"),
    ("pins.radius", "big", "pins.radius", "must be a number"),
    ("pins.per_row", [1, 8, 9], "pins.per_row", "11 counts"),
    ("pins.per_row", [1, 8, 8, 10, 11, 10, 11, 10, 11, 10, 11], "pins.per_row[2]", "parity"),
    ("pins.per_row", [1, 8, 9, 10, 11, 10, 11, 10, 11, 10, 9], "pins.per_row[10]", "11 pins"),
    ("pins.pitch", 0.28, "pins.pitch", "diameter"),
    ("dividers.height", 2.2, "pins.top_row_z", "inside the dividers"),
    ("funnel.opening", 0.05, "funnel.opening", "too narrow"),
    ("funnel.tip_z", 4.4, "funnel.tip_z", "above the top pin"),
    ("funnel.outer_x", 3.0, "funnel.outer_x", "inner face 2.75"),
    ("walls.height", 5.6, "walls.height", "no room above the funnel"),
    ("ball.count", 0, "ball.count", "at least 1"),
    ("release.mode", "stram", "release.mode", "did you mean 'stream'"),
    ("release.interval", 0.05, "release.interval", "too short"),
    ("perturbation.ball_jitter", 0.2, "perturbation.ball_jitter", "at most"),
    ("contacts.pybulet", {}, "contacts.pybulet", "did you mean 'pybullet'"),
    ("contacts.mujoco.bodies", {"pins": {}}, "contacts.mujoco.bodies.pins", "'pin'"),
    ("contacts.mujoco.bodies", {"ball": {"restitution": 1.5}},
     "contacts.mujoco.bodies.ball.restitution", "[0.0, 1.0]"),
    ("funnle", {}, "funnle", "did you mean 'funnel'"),
])
def test_bad_values_name_their_field(path: str, value: object, field: str, hint: str) -> None:
    with pytest.raises(BoardSpecError) as caught:
        BoardSpec.from_dict(_with(path, value))
    assert caught.value.field == field
    assert hint in str(caught.value)
    assert isinstance(caught.value, AnalysisError | ValueError)


def test_direct_construction_is_validated_too() -> None:
    with pytest.raises(BoardSpecError, match=r"pins\.row_pitch"):
        BoardSpec(pins=PinSpec(row_pitch=0.05))


# --- the paper's layout --------------------------------------------------------------------


def test_paper_board_matches_the_published_geometry() -> None:
    spec = paper_board()
    assert (spec.rows, spec.bins) == (11, 12)
    assert pins_per_row(spec) == (1, 8, 9, 10, 11, 10, 11, 10, 11, 10, 11)
    assert len(pin_centres(spec)) == 102
    np.testing.assert_allclose(row_heights(spec), np.linspace(4.104, 2.104, 11))
    np.testing.assert_allclose(divider_positions(spec), np.arange(-2.5, 2.51, 0.5))
    np.testing.assert_allclose(bin_widths(spec), [0.2] + [0.4] * 10 + [0.2])
    lowest = [x for row, _, x, _ in pin_centres(spec) if row == 10]
    np.testing.assert_allclose(lowest, divider_positions(spec))  # the lowest row sits on them
    assert row_heights(spec)[-1] - spec.pins.radius - spec.dividers.height == pytest.approx(0.004)
    assert spec.funnel.opening == pytest.approx(0.29, abs=0.015)
    assert spec.cavity.depth == pytest.approx(0.55)
    assert spec.ball.density == pytest.approx(1000, rel=1e-3)


def test_paper_funnel_walls_span_the_published_ends() -> None:
    spec = paper_board()
    right = next(p for p in board_primitives(spec) if p.name == "funnel_right")
    corners = _box_corners_xz(right)
    inner = corners[np.argsort(corners[:, 0])[:2]]
    outer = corners[np.argsort(corners[:, 0])[2:]]
    assert inner[:, 0].min() == pytest.approx(0.15, abs=1e-9)  # the opening's edge
    assert inner[:, 1].max() == pytest.approx(4.615) and funnel_lowest_z(spec) > 4.30
    assert outer[:, 0].min() == pytest.approx(2.75, abs=1e-9)  # reaches the side wall
    assert 5.25 < outer[:, 1].max() < 5.60


def test_rows_interleave_and_every_path_ends_in_its_own_bin(board: BoardSpec) -> None:
    pitch = board.pins.pitch
    rows = [[x for r, _, x, _ in pin_centres(board) if r == row] for row in range(board.rows)]
    assert rows[0] == [0.0]  # one pin right under the opening
    for upper, lower in itertools.pairwise(rows):
        phase = {round((x / pitch) % 1, 9) for x in upper}, {round((x / pitch) % 1, 9)
                                                            for x in lower}
        assert len(phase[0]) == len(phase[1]) == 1 and phase[0] != phase[1]
    # After one deflection of pitch / 2 per row, a ball is at (k - rows / 2) * pitch.
    ends = (np.arange(board.bins) - board.rows / 2) * pitch
    points = np.column_stack([ends, np.zeros(board.bins), np.full(board.bins, 0.1)])
    assert assign_bins(board, points).tolist() == list(range(board.bins))


def test_triangle_when_pins_per_row_is_omitted() -> None:
    data = _with("pins.per_row", None)
    assert pins_per_row(BoardSpec.from_dict(data)) == tuple(range(1, 12))


# --- primitives ----------------------------------------------------------------------------


def test_primitives_are_named_boxes_and_cylinders(board: BoardSpec) -> None:
    parts = board_primitives(board)
    names = [p.name for p in parts]
    assert len(set(names)) == len(names)
    assert {"floor", "wall_left", "back_wall", "front_glass", "divider_00", "pin_r00_c00"} <= set(
        names)
    assert {p.shape for p in parts} == {"box", "cylinder"}
    assert {p.role for p in parts} == {"pin", "funnel", "divider", "wall", "floor", "glass"}
    assert all(p.static and len(p.pose) == 7 for p in parts)
    for pin in (p for p in parts if p.role == "pin"):
        assert pin.size == (board.pins.radius, board.pins.length / 2)
        np.testing.assert_allclose(np.abs(pin.rotation @ [0, 0, 1]), [0, 1, 0], atol=1e-12)


def test_offset_moves_every_primitive_along_x() -> None:
    spec = paper_board()
    for still, moved in zip(board_primitives(spec), board_primitives(spec, 0.003), strict=True):
        assert moved.pose[0] == pytest.approx(still.pose[0] + 0.003)
        assert moved.pose[1:] == still.pose[1:]


def test_no_two_solids_overlap(board: BoardSpec) -> None:
    parts = board_primitives(board)
    for a, b in itertools.combinations(parts, 2):
        pair = tuple(sorted((a.name, b.name)))
        if pair not in ALLOWED_OVERLAPS:
            assert _overlap_depth(a, b) <= TOUCH, f"{a.name} overlaps {b.name}"
    for pair in ALLOWED_OVERLAPS:
        first, second = (next(p for p in parts if p.name == n) for n in pair)
        assert _overlap_depth(first, second) > 0  # the funnel seals against the wall


# --- release and perturbation --------------------------------------------------------------


def test_start_cloud_is_clear_of_itself_and_of_the_board(board: BoardSpec) -> None:
    for repetition in range(3):
        setup = perturbation(board, repetition, SEED)
        balls = setup.release.positions
        assert balls.shape == (board.ball.count, 3)
        assert pdist(balls).min() >= 2 * board.ball.radius + board.release.gap - 1e-9
        for part in board_primitives(board, setup.board_offset_x):
            clearance = signed_distance(part, balls).min()
            assert clearance >= board.ball.radius + board.release.gap, part.name
        front, back = cavity_faces(board)
        assert np.all((balls[:, 1] > front) & (balls[:, 1] < back))
        assert np.all(balls[:, 2] > board.funnel.tip_z)
        assert np.all(setup.release.times == 0.0)


def test_a_large_cloud_still_fits_the_paper_board() -> None:
    spec = paper_board()
    assert cloud_capacity(spec) >= 1000
    balls = ball_start_positions(spec, SEED, 1000)
    assert pdist(balls).min() >= 2 * spec.ball.radius + spec.release.gap - 1e-9


def test_too_many_balls_name_the_count() -> None:
    spec = BoardSpec.load("small")
    with pytest.raises(BoardSpecError) as caught:
        ball_start_positions(spec, SEED, cloud_capacity(spec) + 1)
    assert caught.value.field == "ball.count"


def test_stream_drops_one_ball_per_interval_above_the_opening(board: BoardSpec) -> None:
    spec = board.replace(release=dataclasses.replace(board.release, mode="stream"))
    schedule = release_schedule(spec, np.random.default_rng(SEED), 20)
    np.testing.assert_allclose(schedule.times, np.arange(20) * spec.release.interval)
    jitter = spec.perturbation.ball_jitter
    assert np.all(np.abs(schedule.positions[:, 0]) <= jitter)
    drop = spec.funnel.tip_z + spec.release.stream_height
    assert np.all(np.abs(schedule.positions[:, 2] - drop) <= jitter)
    for part in board_primitives(spec):
        assert signed_distance(part, schedule.positions).min() > spec.ball.radius


def test_perturbations_are_reproducible_small_and_distinct() -> None:
    spec = paper_board()
    first, again = perturbation(spec, 4, SEED), perturbation(spec, 4, SEED)
    assert first.board_offset_x == again.board_offset_x
    assert np.array_equal(first.release.positions, again.release.positions)
    others = [perturbation(spec, r, SEED) for r in range(4)] + [perturbation(spec, 4, SEED + 1)]
    offsets = {p.board_offset_x for p in [first, *others]}
    assert len(offsets) == 6
    assert all(not np.array_equal(first.ball_jitter, p.ball_jitter) for p in others)
    for p in [first, *others]:
        assert abs(p.board_offset_x) <= 3 * spec.perturbation.board_shift_std
        assert np.abs(p.ball_jitter).max() <= spec.perturbation.ball_jitter


def test_seeds_must_be_non_negative_integers() -> None:
    with pytest.raises(BoardSpecError, match="seed"):
        ball_start_positions(paper_board(), -1)
    with pytest.raises(BoardSpecError, match="repetition"):
        perturbation(paper_board(), -2)


# --- scoring -------------------------------------------------------------------------------


def test_assign_bins_on_hand_placed_points() -> None:
    spec = paper_board()
    xs = [-2.7, -2.45, -0.01, 0.0, 0.01, 0.3, 2.49, 2.7, math.nan]
    points = np.column_stack([xs, np.zeros(len(xs)), np.full(len(xs), 0.1)])
    assert assign_bins(spec, points).tolist() == [0, 1, 5, 6, 6, 6, 10, 11, -1]
    assert assign_bins(spec, points, offset_x=0.1).tolist() == [0, 0, 5, 5, 5, 6, 10, 11, -1]


CASES = {  # name: (x, y, z, speed, outcome)
    "in bin 6": (0.25, 0.0, 0.1, 0.0, "settled"),
    "in bin 0": (-2.65, 0.1, 0.05, 0.01, "settled"),
    "rolling in a bin": (0.25, 0.0, 0.1, 1.0, "moving"),
    "falling": (0.25, 0.0, 3.0, 2.0, "moving"),
    "on the top pin": (0.0, 0.0, 4.104 + 0.1 + 0.045, 0.0, "stuck"),
    "through the floor": (0.25, 0.0, -0.3, 0.0, "below_floor"),
    "beyond a side wall": (3.5, 0.0, 1.0, 0.0, "outside_cavity"),
    "behind the back wall": (0.25, 0.6, 1.0, 0.0, "outside_cavity"),
    "over the top": (0.25, 0.0, 7.5, 0.0, "outside_cavity"),
    "in a pin": (0.5, 0.1, 2.104, 0.0, "tunnelled"),
    "in a divider": (0.0, 0.0, 1.0, 0.0, "tunnelled"),
    "in the glass": (0.25, -0.3, 1.0, 0.0, "tunnelled"),
    "in the funnel": (-1.5, 0.0, 4.95, 0.0, "tunnelled"),
    "nan position": (math.nan, 0.0, 0.1, 0.0, "nan"),
    "nan speed": (0.25, 0.0, 0.1, math.nan, "nan"),
}


def test_classify_every_outcome() -> None:
    spec = paper_board()
    rows = np.array([case[:4] for case in CASES.values()])
    result = classify_balls(spec, rows[:, :3], rows[:, 3], settle_speed=0.05)
    for name, outcome, expected in zip(CASES, result.outcomes, CASES.values(), strict=True):
        assert outcome == expected[4], name
    assert result.counts.tolist() == [1, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0]
    assert result.bin_index.tolist() == [6, 0] + [-1] * (len(CASES) - 2)
    assert result.reasons == {"moving": 2, "stuck": 1, "below_floor": 1, "outside_cavity": 3,
                              "tunnelled": 4, "nan": 2}
    assert (result.settled, result.unsettled) == (2, 3)
    assert result.lost == sum(result.reasons[r] for r in LOSS_REASONS) == 10


def test_classify_follows_the_board_offset() -> None:
    spec = paper_board()
    points = np.array([[0.26, 0.0, 0.1], [0.06, 0.0, 0.1]])
    result = classify_balls(spec, points, np.zeros(2), offset_x=0.1)
    assert result.outcomes == ("settled", "tunnelled")  # the second is now in divider_05
    assert result.bin_index.tolist() == [6, -1]


def test_classify_checks_its_inputs() -> None:
    with pytest.raises(BoardSpecError, match="speeds"):
        classify_balls(paper_board(), np.zeros((3, 3)), np.zeros(2))
    with pytest.raises(BoardSpecError, match="positions"):
        classify_balls(paper_board(), np.zeros((3, 2)), np.zeros(3))


# --- helpers: cross-sections of prisms along y ---------------------------------------------


def _box_corners_xz(box: Primitive) -> np.ndarray:
    hx, _, hz = box.size
    local = np.array([[sx * hx, 0.0, sz * hz] for sx in (-1, 1) for sz in (-1, 1)])
    return (local @ box.rotation.T + box.position)[:, [0, 2]]


def _y_range(part: Primitive) -> tuple[float, float]:
    half = part.size[1]  # box half depth; a pin's half length (its axis is along y)
    return part.pose[1] - half, part.pose[1] + half


def _overlap_depth(a: Primitive, b: Primitive) -> float:
    """How deep two board solids interpenetrate (<= 0: apart or touching).

    Every board solid is a prism along y (pins turned onto y, boxes turned about y), so
    the depth is the smaller of the y overlap and the x-z cross-sections' overlap.
    """
    (a0, a1), (b0, b1) = _y_range(a), _y_range(b)
    depth_y = min(a1, b1) - max(a0, b0)
    y_mid = (max(a0, b0) + min(a1, b1)) / 2
    if a.shape == b.shape == "cylinder":
        centres = [(p.pose[0], p.pose[2]) for p in (a, b)]
        gap = math.dist(*centres) - a.size[0] - b.size[0]
        return min(depth_y, -gap)
    if "cylinder" in (a.shape, b.shape):
        pin, box = (a, b) if a.shape == "cylinder" else (b, a)
        centre = np.array([[pin.pose[0], y_mid, pin.pose[2]]])
        return min(depth_y, pin.size[0] - float(signed_distance(box, centre)[0]))
    return min(depth_y, _rect_overlap(_box_corners_xz(a), _box_corners_xz(b)))


def _rect_overlap(p: np.ndarray, q: np.ndarray) -> float:
    """Separating-axis overlap of two rectangles given by their corners (< 0: apart)."""
    depth = math.inf
    for corners in (p, q):
        for axis in (corners[1] - corners[0], corners[2] - corners[0]):
            unit = axis / np.linalg.norm(axis)
            pa, qa = p @ unit, q @ unit
            depth = min(depth, min(pa.max(), qa.max()) - max(pa.min(), qa.min()))
    return depth
