"""A lone ball on the board with exact collisions: the law no time step or soft contact shapes.

Usage: python research/exact_lone_ball.py [--balls 1000] [--seed 0] [--restitution 0.70]
                                          [--friction 0.25] [--threshold 0.2]
                                          [--restitution-at-3 E3] [--board NAME_OR_TOML]

Both engines' lone (streamed, one at a time) balls come out with a law of the right width
but disagree on its shape: PyBullet's is flat (excess kurtosis -0.38), MuJoCo's is the
binomial's (-0.18) (docs/research/physics-notebook.md, "Are the rows independent?").
Each engine steps a contact model with its own numerics: a time step, a soft or
impulsive contact, a contact distance. This script follows the same balls with none of
those: an event-driven flight of a solid sphere (I = 2/5 m r^2, spin about the pins'
axis) between exact impacts, in the board's x-z plane (the pins span the cavity's depth,
so a lone ball's y plays no part).

The contact law is the rigid one both engines aim at: at each impact the normal velocity
reverses with restitution e (e = 0 when the ball approaches slower than ``--threshold``,
PyBullet's restitution velocity threshold; ``--restitution-at-3`` makes e depend on the
approach speed, as a real ball's does); Coulomb friction mu stops the contact point's
slip if mu times the normal impulse suffices, else slides. A ball that ends an impact on a
pin's upper half without bouncing rolls on it without slipping (closed form: it leaves the
pin where gravity can no longer hold it on the curve), so a trial never needs a time step.
Scenery is every static solid of the board from ``board_primitives`` (pins as circles,
boxes as polygons with round corners of radius 0), so the funnel's tips and lower faces
and the side walls are in play; glass and back wall are not (no y).

The release is the bench's stream (``perturbation``: repetition 0 of ``--seed``, the same
drop points and board shift as ``walk_probe.py ENGINE --seed S``), and the output is
``walk_probe``'s summary of the walks and bins, so the two compare line by line.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from dataclasses import dataclass

import numpy as np
import walk_probe
from scipy.spatial.transform import Rotation

from galton.analysis.board import BoardSpec
from galton.analysis.board_geometry import board_primitives
from galton.analysis.board_layout import divider_top, row_heights
from galton.analysis.board_release import Perturbation, perturbation
from galton.analysis.board_scoring import assign_bins

GRAVITY = 9.81
FALL = np.array([0.0, -GRAVITY])  # gravity's acceleration in the x-z plane
HORIZON_S = 0.25  # flight looked ahead per search for the next impact
MAX_EVENTS = 5000  # impacts before a ball counts as caught
ROLL_FACTOR = 5 / 7  # a rolling solid sphere's acceleration along a slope, over g's
STICK_FACTOR = 2 / 7  # m / impulse that stops a solid sphere's contact-point slip
NUDGE = 1e-7  # m put between a ball and the pin it rolls off, so it does not hit it again


@dataclass(frozen=True)
class Contact:
    """A surface's law: restitution, friction, and the approach speed under which e is 0."""

    restitution: float
    friction: float
    threshold: float
    restitution_at_3: float | None = None  # e at 3 m/s; linear in the approach speed from 1 m/s
    plastic_exponent: float | None = None  # e = restitution * (v / 1 m/s) ** -exponent
    cap: float = 0.95  # the most a speed-dependent law may give (an engine's own ceiling)
    # Judge the speed by the ball's whole velocity, not its normal part: what an engine that
    # sets each ball's bounce between steps, from its speed in flight, can do.
    whole_speed: bool = False

    def bounce(self, approach: float, speed: float | None = None) -> float:
        """e for this approach speed (normal part; ``speed``: the whole one): 0 below the
        threshold, else constant or speed-dependent."""
        if approach < self.threshold:
            return 0.0
        if self.whole_speed and speed is not None:
            approach = speed
        if self.plastic_exponent is not None:
            return min(self.cap, self.restitution * approach ** -self.plastic_exponent)
        if self.restitution_at_3 is None:
            return self.restitution
        slope = (self.restitution_at_3 - self.restitution) / 2.0
        return min(self.cap, max(0.0, self.restitution + slope * (approach - 1.0)))


@dataclass
class Ball:
    """Centre (x, z), velocity (vx, vz) and spin about +y, in the board's frame."""

    p: np.ndarray
    v: np.ndarray
    spin: float


@dataclass(frozen=True)
class Scenery:
    """Pins (circles of radius ``pin_reach`` = pin radius + ball radius around their axes),
    polygon edges (start, direction, length, outward normal) and corners."""

    pins: np.ndarray
    pin_reach: float
    edges: list[tuple[np.ndarray, np.ndarray, float, np.ndarray]]
    corners: np.ndarray
    edge_low: np.ndarray  # each edge's bounding box
    edge_high: np.ndarray


def scenery(board: BoardSpec) -> Scenery:
    """The board's static solids in the x-z plane, unshifted."""
    pins, edges, corners = [], [], []
    for prim in board_primitives(board, 0.0):
        x, _, z, *quat = prim.pose
        if prim.shape == "cylinder":
            pins.append((x, z))
            continue
        if prim.role in ("glass", "floor") or prim.name == "back_wall":
            continue
        hx, _, hz = prim.size
        rot = Rotation.from_quat(quat).as_matrix()[np.ix_([0, 2], [0, 2])]
        local = np.array([[hx, hz], [-hx, hz], [-hx, -hz], [hx, -hz]])  # counter-clockwise
        square = np.array([x, z]) + local @ rot.T
        corners += square.tolist()
        for a, b in zip(square, np.roll(square, -1, axis=0), strict=True):
            length = float(np.linalg.norm(b - a))
            direction = (b - a) / length
            edges.append((a, direction, length, np.array([direction[1], -direction[0]])))
    ends = np.array([[start, start + direction * length] for start, direction, length, _ in edges])
    return Scenery(np.array(pins), board.pins.radius + board.ball.radius, edges,
                   np.array(corners), ends.min(axis=1), ends.max(axis=1))


def _position(ball: Ball, t: float) -> np.ndarray:
    return ball.p + ball.v * t + 0.5 * FALL * t * t


def _velocity(ball: Ball, t: float) -> np.ndarray:
    return ball.v + FALL * t


def _circle_hit(ball: Ball, centre: np.ndarray, reach: float, horizon: float) -> float | None:
    """When the centre first reaches distance ``reach`` of ``centre`` while approaching."""
    d0, v, a = ball.p - centre, ball.v, 0.5 * FALL
    coefficients = np.array([a @ a, 2 * a @ v, v @ v + 2 * a @ d0, 2 * v @ d0,
                             d0 @ d0 - reach * reach])
    roots = np.roots(coefficients)
    real = np.sort(roots[np.abs(roots.imag) < 1e-6].real)
    for t in real[(real > 1e-9) & (real <= horizon)]:
        if (_position(ball, t) - centre) @ _velocity(ball, t) < 0:
            return float(t)
    return None


def _edge_hit(ball: Ball, edge: tuple, radius: float, horizon: float) -> float | None:
    """When the ball's surface first meets a polygon edge from outside, within its length."""
    start, direction, length, normal = edge
    gap = normal @ (ball.p - start) - radius
    coefficients = np.array([-0.5 * GRAVITY * normal[1], normal @ ball.v, gap])
    for t in np.sort(np.roots(coefficients)):
        if abs(t.imag) > 1e-9 or not 1e-9 < t.real <= horizon:
            continue
        t = float(t.real)
        along = direction @ (_position(ball, t) - start)
        if 0 <= along <= length and normal @ _velocity(ball, t) < 0:
            return t
    return None


def _near(points: np.ndarray, low: np.ndarray, high: np.ndarray, reach: float) -> np.ndarray:
    return np.nonzero(np.all((points >= low - reach) & (points <= high + reach), axis=1))[0]


def next_impact(ball: Ball, world: Scenery, radius: float,
                horizon: float) -> tuple[float, np.ndarray, str] | None:
    """The first impact within ``horizon``: its time, the contact normal, what was hit."""
    ts = np.linspace(0, horizon, 9)
    path = np.array([_position(ball, t) for t in ts])
    apex = ball.v[1] / GRAVITY
    if 0 < apex < horizon:
        path = np.vstack([path, _position(ball, apex)])
    low, high = path.min(axis=0), path.max(axis=0)
    best: tuple[float, np.ndarray, str] | None = None
    for i in _near(world.pins, low, high, world.pin_reach + 0.01):
        t = _circle_hit(ball, world.pins[i], world.pin_reach, horizon)
        if t is not None and (best is None or t < best[0]):
            best = (t, world.pins[i], "pin")
    for i in _near(world.corners, low, high, radius + 0.01):
        t = _circle_hit(ball, world.corners[i], radius, horizon)
        if t is not None and (best is None or t < best[0]):
            best = (t, world.corners[i], "corner")
    for i in np.nonzero(np.all((world.edge_low <= high + radius + 0.01)
                               & (world.edge_high >= low - radius - 0.01), axis=1))[0]:
        edge = world.edges[i]
        t = _edge_hit(ball, edge, radius, horizon)
        if t is not None and (best is None or t < best[0]):
            best = (t, edge[3], "edge")
    if best is None:
        return None
    t, where, kind = best
    if kind == "edge":
        return t, where, kind
    offset = _position(ball, t) - where
    return t, offset / np.linalg.norm(offset), kind


def impact(ball: Ball, normal: np.ndarray, radius: float, law: Contact) -> float:
    """Apply one rigid impact (per unit mass); returns the normal speed it leaves with."""
    tangent = np.array([-normal[1], normal[0]])
    approach = -ball.v @ normal
    e = law.bounce(approach, float(np.linalg.norm(ball.v)))
    normal_impulse = (1 + e) * approach
    slip = ball.v @ tangent + ball.spin * radius
    stick = -slip * STICK_FACTOR
    limit = law.friction * normal_impulse
    tangent_impulse = stick if abs(stick) <= limit else -math.copysign(limit, slip)
    ball.v = ball.v + normal_impulse * normal + tangent_impulse * tangent
    ball.spin += tangent_impulse * radius / (0.4 * radius * radius)
    return e * approach


def roll_off(ball: Ball, centre: np.ndarray, reach: float, radius: float) -> None:
    """A ball resting on a pin's upper half rolls off it; place it where it leaves.

    Energy: (7/10) u^2 + g z is kept while rolling; it leaves where g cos(phi) = u^2 / reach
    (phi from the top), so cos(phi) = (u0^2 / (g reach) + (10/7) cos(phi0)) / (17/7).
    A ball that the pin cannot hold even now (g cos(phi0) <= u0^2 / reach) just flies on.
    """
    offset = (ball.p - centre) / reach
    phi0 = math.atan2(offset[0], offset[1])
    u0 = float(ball.v @ np.array([math.cos(phi0), -math.sin(phi0)]))  # along +phi
    if GRAVITY * math.cos(phi0) <= u0 * u0 / reach:
        ball.p = centre + offset * (reach + NUDGE)
        return
    side = math.copysign(1.0, phi0) if phi0 != 0 else math.copysign(1.0, u0 or 1.0)
    if u0 * phi0 < 0 and 0.7 * u0 * u0 > GRAVITY * reach * (1 - math.cos(phi0)):
        side = -side  # it rolls over the top
    cos_leave = (u0 * u0 / (GRAVITY * reach) + 10 / 7 * math.cos(phi0)) / (17 / 7)
    phi = side * math.acos(cos_leave)
    speed = math.sqrt(GRAVITY * reach * cos_leave)
    ball.p = centre + (reach + NUDGE) * np.array([math.sin(phi), cos_leave])
    ball.v = side * speed * np.array([cos_leave, -math.sin(phi)])  # d(phi)/dt has the side's sign
    ball.spin = side * speed / radius


class Follower:
    """Downward crossings of each row's axis (first and last) and the bin, per ball."""

    def __init__(self, board: BoardSpec, count: int) -> None:
        self.heights = np.asarray(row_heights(board))
        self.board = board
        self.bin_z = divider_top(board) - board.ball.radius
        self.first = np.full((count, board.rows), np.nan)
        self.last = np.full((count, board.rows), np.nan)
        self.bins = np.full(count, -1)

    def note(self, index: int, ball: Ball, duration: float) -> bool:
        """Record the crossings of one flight; True if the ball reached its bin in it."""
        for row, height in enumerate(self.heights):
            for t in _downward_times(ball, height, duration):
                x = float(_position(ball, t)[0])
                self.last[index, row] = x
                if np.isnan(self.first[index, row]):
                    self.first[index, row] = x
        landing = _downward_times(ball, self.bin_z, duration)
        if landing:
            x, z = _position(ball, landing[0])
            self.bins[index] = int(assign_bins(self.board, np.array([[x, 0.0, z]]))[0])
            return True
        return False


def _downward_times(ball: Ball, height: float, duration: float) -> list[float]:
    """Times in (0, duration] at which the centre goes down through z = height."""
    roots = np.roots([-0.5 * GRAVITY, ball.v[1], ball.p[1] - height])
    return sorted(float(t.real) for t in roots
                  if abs(t.imag) < 1e-12 and 0 < t.real <= duration
                  and _velocity(ball, float(t.real))[1] < 0)


def fall(ball: Ball, index: int, world: Scenery, radius: float, law: Contact,
         seen: Follower) -> int:
    """Follow one ball to its bin; returns the number of impacts (MAX_EVENTS: caught)."""
    for events in range(MAX_EVENTS):
        hit = next_impact(ball, world, radius, HORIZON_S)
        duration = HORIZON_S if hit is None else hit[0]
        if seen.note(index, ball, duration):
            return events
        ball.p, ball.v = _position(ball, duration), _velocity(ball, duration)
        if hit is None:
            continue
        _, normal, kind = hit
        leaving = impact(ball, normal, radius, law)
        if kind == "pin" and leaving < 1e-3 and normal[1] > 0:
            centre = ball.p - normal * world.pin_reach
            roll_off(ball, centre, world.pin_reach, radius)
    return MAX_EVENTS


def run(board: BoardSpec, shake: Perturbation, law: Contact) -> tuple[Follower, list[int]]:
    world = scenery(board)
    count = len(shake.release.times)
    seen = Follower(board, count)
    impacts = []
    for index, start in enumerate(shake.release.positions):
        ball = Ball(np.array([start[0] - shake.board_offset_x, start[2]]), np.zeros(2), 0.0)
        impacts.append(fall(ball, index, world, board.ball.radius, law, seen))
    return seen, impacts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--balls", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--restitution", type=float, default=0.70)
    parser.add_argument("--friction", type=float, default=0.25)
    parser.add_argument("--threshold", type=float, default=0.2)
    parser.add_argument("--restitution-at-3", type=float, default=None,
                        help="e at 3 m/s: e then falls (or rises) linearly with the approach "
                             "speed from --restitution at 1 m/s (clipped to 0..--cap)")
    parser.add_argument("--plastic-exponent", type=float, default=None,
                        help="e = --restitution * (v / 1 m/s) ** -P, capped at --cap; Johnson's "
                             "elastic-plastic impact gives P = 1/4")
    parser.add_argument("--cap", type=float, default=0.95,
                        help="the highest e a speed-dependent law gives (MuJoCo's contact "
                             "reaches about 0.72 at its default 2 ms step)")
    parser.add_argument("--whole-speed", action="store_true",
                        help="the law reads the ball's whole speed, not the normal approach "
                             "(as an engine setting each ball's bounce between steps would)")
    parser.add_argument("--board", default="paper")
    args = parser.parse_args()
    law = Contact(args.restitution, args.friction, args.threshold, args.restitution_at_3,
                  args.plastic_exponent, args.cap, args.whole_speed)
    print(json.dumps(trial(args.board, args.balls, args.seed, law)))


def trial(board_name: str, balls: int, seed: int, law: Contact) -> dict:
    """One stream trial of lone balls under this law, as walk_probe summarises it."""
    board = walk_probe.released(board_name, balls)
    shake = perturbation(board, 0, seed, balls)
    seen, impacts = run(board, shake, law)
    return {"model": "exact", "board": board.name, "seed": seed,
            "contact": dataclasses.asdict(law), "board_offset_x": shake.board_offset_x,
            "impacts_median": float(np.median(impacts)),
            "caught_after_max_impacts": int(sum(i >= MAX_EVENTS for i in impacts)),
            **walk_probe.summarise(seen, board, shake)}


if __name__ == "__main__":
    main()
