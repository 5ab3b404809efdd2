"""Where a ``BoardSpec`` puts things (pins, dividers, funnel, cavity), and whether it can work.

How the pin rows meet the bins (the derivation behind ``row_x``):

* The lowest row sits on the dividers, one pin on each, so it has bins - 1 pins at
  x = (j - (bins - 2) / 2) * pitch: -2.5 .. 2.5 for the paper's 12 bins and 0.5 m pitch.
* Every row is centred on x = 0, the funnel's axis: a row of n pins has them at
  x = (j - (n - 1) / 2) * pitch. A row with an odd count has a pin at x = 0, an even count
  has pins at +-pitch / 2; so rows whose counts alternate in parity interleave, each shifted
  by pitch / 2 from the next: a hexagonal lattice.
* Going up from the lowest row (bins - 1 = rows pins), parity alternates rows - 1 times, so
  the top row always has an odd count, hence a pin right under the funnel opening. The
  paper's single top pin at x = 0 splits the stream; the 8-pin second row (+-0.25 .. +-1.75)
  then sits on the gaps either side of it, and so on down.
* A ball meets one pin per row and leaves it pitch / 2 to the left or right, so after the
  rows rows it is at x = (k - rows / 2) * pitch for k = 0 .. rows: exactly the bins' centre
  lines (between two dividers; the outermost two between a divider and a wall). With
  fair, independent deflections, k is Binomial(rows, 1/2) and bins = rows + 1.
* The paper's rows 2-4 (8, 9, 10 pins) widen the triangle a ball can reach (1, 2, 3, ...)
  to the side walls; with ``per_row`` None the board is that triangle.

Checks (``spec_problems``) yield (field, problem) pairs, first problem first; ``BoardSpec``
raises the first as ``BoardSpecError``. They run in an order where each may trust earlier
ones (types before ranges before cross-field rules).
"""

from __future__ import annotations

import difflib
import itertools
import math
from collections.abc import Iterable, Iterator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from galton.analysis.board import BoardSpec

ENGINES = ("mujoco", "pybullet", "ode", "dart")
BODY_ROLES = ("ball", "pin", "funnel", "divider", "wall", "glass", "floor")
RELEASE_MODES = ("all-at-once", "stream")
GRAVITY = 9.81
MAX_BOARD_SHIFT_STD = 0.05
Problem = tuple[str, str]


def did_you_mean(name: str, options: Iterable[str]) -> str:
    close = difflib.get_close_matches(name, list(options), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


# --- layout --------------------------------------------------------------------------------


def pins_per_row(spec: BoardSpec) -> tuple[int, ...]:
    """Pins in each row from the top: the spec's list, or the triangle 1, 2, ..., rows."""
    per_row = spec.pins.per_row
    return per_row if per_row is not None else tuple(range(1, spec.rows + 1))


def row_heights(spec: BoardSpec) -> tuple[float, ...]:
    """The z of each pin row's axis, from the top."""
    return tuple(spec.pins.top_row_z - r * spec.pins.row_pitch for r in range(spec.rows))


def row_x(count: int, pitch: float) -> tuple[float, ...]:
    """x of ``count`` pins centred on x = 0 (see the module docstring for why centred)."""
    return tuple((j - (count - 1) / 2) * pitch for j in range(count))


def pin_centres(spec: BoardSpec) -> list[tuple[int, int, float, float]]:
    """(row, column, x, z) of every pin; rows from the top, columns from -x."""
    centres = []
    for row, (count, z) in enumerate(zip(pins_per_row(spec), row_heights(spec), strict=True)):
        centres += [(row, col, x, z) for col, x in enumerate(row_x(count, spec.pins.pitch))]
    return centres


def divider_positions(spec: BoardSpec) -> tuple[float, ...]:
    """x of the bins - 1 dividers: the spec's list, or one under each pin of the lowest row."""
    given = spec.dividers.x_positions
    return given if given is not None else row_x(spec.bins - 1, spec.pins.pitch)


def divider_top(spec: BoardSpec) -> float:
    return spec.floor.z + spec.dividers.height


def bin_widths(spec: BoardSpec) -> tuple[float, ...]:
    """Free width of each bin (face to face), from -x to +x."""
    half = spec.dividers.thickness / 2
    faces = [-spec.walls.inner_x - half, *divider_positions(spec), spec.walls.inner_x + half]
    return tuple(b - a - 2 * half for a, b in itertools.pairwise(faces))


def cavity_faces(spec: BoardSpec) -> tuple[float, float]:
    """y of the glass's inner face (front, -y) and of the back wall's inner face (+y)."""
    half = spec.cavity.depth / 2
    return spec.cavity.centre_y - half, spec.cavity.centre_y + half


def funnel_lowest_z(spec: BoardSpec) -> float:
    """z of the funnel's lowest edge, the box corner under the inner tip."""
    return spec.funnel.tip_z - spec.funnel.thickness * math.cos(math.radians(spec.funnel.angle_deg))


def funnel_outer_top_z(spec: BoardSpec) -> float:
    """z of the funnel's upper surface where it ends, at x = +-outer_x."""
    f = spec.funnel
    return f.tip_z + (f.outer_x - f.opening / 2) * math.tan(math.radians(f.angle_deg))


def board_top(spec: BoardSpec) -> float:
    return spec.floor.z + spec.walls.height


# --- checks --------------------------------------------------------------------------------


def spec_problems(spec: BoardSpec) -> Iterator[Problem]:
    """Every problem of the spec, in an order where each check may trust the earlier ones."""
    for group in (_scalar_problems, _pin_problems, _bin_problems, _funnel_problems,
                  _release_problems, _contact_problems):
        yield from group(spec)


def _number(value: Any, where: str, low: float, high: float = math.inf,
            low_open: bool = True) -> Iterator[Problem]:
    if isinstance(value, bool) or not isinstance(value, int | float):
        yield where, f"must be a number, got {type(value).__name__} {value!r}"
    elif not math.isfinite(value) or value < low or (low_open and value == low) or value > high:
        bound = f"({low}, {high}]" if low_open else f"[{low}, {high}]"
        yield where, f"must be a finite number in {bound}, got {value!r}"


def _integer(value: Any, where: str, low: int) -> Iterator[Problem]:
    if isinstance(value, bool) or not isinstance(value, int):
        yield where, f"must be an integer, got {type(value).__name__} {value!r}"
    elif value < low:
        yield where, f"must be at least {low}, got {value}"


PARTS = ("primitives", "mesh")  # BoardSpec.parts


def _scalar_problems(spec: BoardSpec) -> Iterator[Problem]:
    """Types and signs of every single-number field."""
    if not isinstance(spec.name, str) or not spec.name:
        yield "name", f"must be a non-empty string, got {spec.name!r}"
    for where, value in (("rows", spec.rows), ("bins", spec.bins), ("ball.count", spec.ball.count)):
        yield from _integer(value, where, 1)
    yield from _integer(spec.seed, "seed", 0)
    positive = {
        "pins": ("radius", "length", "pitch", "row_pitch"),
        "funnel": ("angle_deg", "opening", "thickness", "outer_x"),
        "dividers": ("thickness", "height"), "walls": ("inner_x", "thickness", "height"),
        "cavity": ("depth", "glass_thickness", "back_thickness"), "floor": ("thickness",),
        "ball": ("radius", "mass"), "release": ("interval", "stream_height"),
    }
    for section, names in positive.items():
        for name in names:
            yield from _number(getattr(getattr(spec, section), name), f"{section}.{name}", 0.0)
    anywhere = (("pins.top_row_z", spec.pins.top_row_z), ("funnel.tip_z", spec.funnel.tip_z),
                ("cavity.centre_y", spec.cavity.centre_y), ("floor.z", spec.floor.z))
    for where, height in anywhere:
        yield from _number(height, where, -math.inf)
    yield from _number(spec.release.gap, "release.gap", 0.0, low_open=False)
    if spec.ball.inertia is not None:
        yield from _number(spec.ball.inertia, "ball.inertia", 0.0)
    if spec.parts not in PARTS:
        yield "parts", f"must be one of {', '.join(PARTS)}, got {spec.parts!r}"
    yield from _number(spec.perturbation.board_shift_std, "perturbation.board_shift_std", 0.0,
                       MAX_BOARD_SHIFT_STD, low_open=False)
    yield from _number(spec.perturbation.ball_jitter, "perturbation.ball_jitter", 0.0,
                       low_open=False)


def _pin_problems(spec: BoardSpec) -> Iterator[Problem]:
    """Row counts that form a lattice ending on the dividers; gaps a ball can pass."""
    pins, ball_d = spec.pins, 2 * spec.ball.radius
    if spec.bins != spec.rows + 1:
        yield "bins", (f"must be rows + 1 = {spec.rows + 1} (the statistics assume "
                       f"Binomial(rows, 1/2) over rows + 1 bins), got {spec.bins}")
        return
    yield from _per_row_problems(spec)
    if pins.pitch - 2 * pins.radius <= ball_d:
        yield "pins.pitch", (f"leaves {pins.pitch - 2 * pins.radius:.3f} m between pins of a row;"
                             f" a ball needs more than its diameter {ball_d:.3f} m")
    diagonal = math.hypot(pins.pitch / 2, pins.row_pitch) - 2 * pins.radius
    if diagonal <= ball_d:
        yield "pins.row_pitch", (f"leaves {diagonal:.3f} m between diagonal neighbours; a ball "
                                 f"needs more than {ball_d:.3f} m")
    if pins.length > spec.cavity.depth:
        yield "pins.length", (f"{pins.length} m is longer than the cavity "
                              f"({spec.cavity.depth} m): pins would cut the glass")


def _per_row_problems(spec: BoardSpec) -> Iterator[Problem]:
    per_row = spec.pins.per_row
    if per_row is None:
        return
    if not isinstance(per_row, tuple) or len(per_row) != spec.rows:
        yield "pins.per_row", f"must list {spec.rows} counts (one per row), got {per_row!r}"
        return
    for row, count in enumerate(per_row):
        yield from _integer(count, f"pins.per_row[{row}]", 1)
    for row in range(1, spec.rows):
        if (per_row[row] - per_row[row - 1]) % 2 == 0:
            yield f"pins.per_row[{row}]", (
                f"{per_row[row]} pins below a row of {per_row[row - 1]}: neighbouring rows must "
                "differ in parity (odd, even, odd ...) so that they interleave")
    if per_row[-1] != spec.bins - 1:
        yield f"pins.per_row[{spec.rows - 1}]", (
            f"the lowest row must have bins - 1 = {spec.bins - 1} pins, one on each divider; "
            f"got {per_row[-1]}")
    widest = (max(per_row) - 1) / 2 * spec.pins.pitch + spec.pins.radius + 2 * spec.ball.radius
    if widest > spec.walls.inner_x:
        yield "pins.per_row", (f"a row of {max(per_row)} pins needs walls at +-{widest:.3f} m "
                               "for a ball to pass its ends; walls.inner_x is "
                               f"{spec.walls.inner_x}")


def _bin_problems(spec: BoardSpec) -> Iterator[Problem]:
    """Dividers inside the walls, bins wider than a ball, the lowest pins above the dividers."""
    given = spec.dividers.x_positions
    if given is not None and (
            not isinstance(given, tuple) or len(given) != spec.bins - 1
            or any(b <= a for a, b in itertools.pairwise(given))):
        yield "dividers.x_positions", (f"must be {spec.bins - 1} increasing x values, "
                                       f"got {given!r}")
        return
    ball_d = 2 * spec.ball.radius
    for i, width in enumerate(bin_widths(spec)):
        if width <= ball_d:
            yield "dividers.x_positions", (f"leave bin {i} {width:.3f} m wide; a ball needs "
                                          f"more than {ball_d:.3f} m (walls.inner_x, pins.pitch "
                                          "or dividers.thickness)")
            return
    lowest_pin_bottom = row_heights(spec)[-1] - spec.pins.radius
    if lowest_pin_bottom < divider_top(spec):
        yield "pins.top_row_z", (f"puts the lowest pins' bottom at z = {lowest_pin_bottom:.3f}, "
                                 f"inside the dividers (top z = {divider_top(spec):.3f}); raise "
                                 f"it by {divider_top(spec) - lowest_pin_bottom:.3f} m")
    if spec.cavity.depth <= ball_d + 2 * spec.release.gap:
        yield "cavity.depth", f"{spec.cavity.depth} m leaves no room for a {ball_d} m ball"


def _funnel_problems(spec: BoardSpec) -> Iterator[Problem]:
    """A funnel a ball passes, clear of the top pin, inside walls tall enough to hold a cloud."""
    f, ball_d = spec.funnel, 2 * spec.ball.radius
    if f.angle_deg >= 90:
        yield "funnel.angle_deg", f"must be below 90 (a slope from horizontal), got {f.angle_deg}"
    if f.opening <= ball_d:
        yield "funnel.opening", f"{f.opening} m is too narrow for a {ball_d} m ball"
    if not f.opening / 2 < f.outer_x <= spec.walls.inner_x:
        yield "funnel.outer_x", (f"must lie between the opening's edge {f.opening / 2} and the "
                                 f"side walls' inner face {spec.walls.inner_x}, got {f.outer_x}")
    if f.angle_deg >= 90 or f.opening <= ball_d:
        return
    top_pin_top = spec.pins.top_row_z + spec.pins.radius
    if funnel_lowest_z(spec) - top_pin_top < ball_d:
        yield "funnel.tip_z", (f"puts the funnel's lowest edge at z = {funnel_lowest_z(spec):.3f},"
                               f" less than a ball diameter above the top pin (top at "
                               f"z = {top_pin_top:.3f})")
    if funnel_outer_top_z(spec) + 2 * ball_d > board_top(spec):
        yield "walls.height", (f"leaves no room above the funnel (its top at z = "
                               f"{funnel_outer_top_z(spec):.3f}); make the walls taller")


def _release_problems(spec: BoardSpec) -> Iterator[Problem]:
    """A known mode; stream balls that fall clear of each other and fit through the opening."""
    release, radius = spec.release, spec.ball.radius
    if release.mode not in RELEASE_MODES:
        yield "release.mode", (f"{release.mode!r} is not one of {', '.join(RELEASE_MODES)}"
                               f"{did_you_mean(str(release.mode), RELEASE_MODES)}")
    room = min(spec.funnel.opening / 2, spec.cavity.depth / 2) - radius - release.gap
    if spec.perturbation.ball_jitter > room:
        yield "perturbation.ball_jitter", (f"{spec.perturbation.ball_jitter} m could push a "
                                           f"streamed ball into the funnel; at most {room:.3f}")
    if release.stream_height < radius:
        yield "release.stream_height", (f"must be at least the ball radius {radius} so a "
                                        f"streamed ball starts above the funnel tip")
    fall = 2 * radius + 2 * spec.perturbation.ball_jitter + release.gap
    least = math.sqrt(2 * fall / GRAVITY)
    if release.interval < least:
        yield "release.interval", (f"{release.interval} s is too short: a ball falls clear of "
                                   f"the next one ({fall:.3f} m) only after {least:.3f} s")


def _contact_problems(spec: BoardSpec) -> Iterator[Problem]:
    """Known engines and body roles; friction >= 0; restitution in [0, 1]."""
    contacts: Any = spec.contacts  # as read from a file: checked here, not trusted
    if not isinstance(contacts, dict):
        yield "contacts", f"must be a table of engine name to settings, got {contacts!r}"
        return
    for engine, settings in spec.contacts.items():
        if engine not in ENGINES:
            yield f"contacts.{engine}", (f"is not an engine{did_you_mean(engine, ENGINES)}; "
                                         f"known: {', '.join(ENGINES)}")
            continue
        yield from _surface_problems(f"contacts.{engine}", settings.params, settings.bodies)


def _surface_problems(where: str, params: Any, bodies: Any) -> Iterator[Problem]:
    if not isinstance(params, dict) or not all(isinstance(k, str) for k in params):
        yield f"{where}.params", f"must be a table of parameter name to value, got {params!r}"
    if not isinstance(bodies, dict):
        yield f"{where}.bodies", f"must be a table of body role to surface, got {bodies!r}"
        return
    for role, surface in bodies.items():
        at = f"{where}.bodies.{role}"
        if role not in BODY_ROLES:
            yield at, (f"is not a body role{did_you_mean(role, BODY_ROLES)}; "
                       f"known: {', '.join(BODY_ROLES)}")
            continue
        if surface.friction is not None:
            yield from _number(surface.friction, f"{at}.friction", 0.0, low_open=False)
        if surface.restitution is not None:
            yield from _number(surface.restitution, f"{at}.restitution", 0.0, 1.0, low_open=False)
