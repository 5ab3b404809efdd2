"""No sleeping balanced on a pin: MuJoCo's island sleeping can freeze a ball at an unstable
rest, and this wakes it.

A ball that arrives almost exactly on top of a fixed round support (a pin's apex) slows
there below ``sleep_tolerance`` for MuJoCo's ten steps and falls asleep. Real balls roll off
such a crown: the rest is unstable, only sleeping keeps it. On the paper board about one
ball in 5,000 ended its trial asleep on a pin's top that way, counted in no bin.

The same freeze holds arches. A ball on a pin's shoulder (15-25 degrees from its top) is
pinned there by a neighbour wedged against the side of the pin above; the neighbour slides
down that side at about the sleep tolerance (5 mm/s), so the pair falls asleep, and stays
for good. Awake, the same pair collapses within 3 s (paper board, MuJoCo all-at-once, 500
balls: 3 of 190 trials ended with such a pair; tests/daemon/engines/test_mujoco_engine.py rebuilds
one).

So every few steps the engine looks at the balls that fell asleep since its last look. One
held up by a single contact, with a round geom of the fixed scenery, whose normal is within
CROWN_DEGREES of straight up, is woken and kept awake (sleep policy "never") until it leaves
that crown; then it may sleep again like any other ball. A ball resting there alone rolls
off; one held by its neighbours keeps their island awake until they slip or HOLD_LIMIT_S
passes. Balls at rest on a floor, in a pile or wedged between two supports are never
touched. Only the balls that have just fallen asleep are examined, a few geometric queries
each.

Crowns of moving bodies (a ball on top of another ball) are left alone: that ball is in a
pile already, in its bin, and holding it awake kept its whole pile's island awake (8 % slower
500-ball trials when tried). A ball balanced within 0.1 mm of a pin's top rolls off in about
a second; one still there after HOLD_LIMIT_S is held by something else for real (a
neighbour and the glass, say): it is let go, may sleep there, and is not held again until it
has woken.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import mujoco
import numpy as np

from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

CROWN_DEGREES = 30.0  # a ball on one round support this close to its top cannot rest alone
SUPPORT_COSINE = 0.17  # a contact whose normal is within 80 degrees of up bears weight
TOUCH = 1e-3  # m: geoms closer than this touch
HOLD_LIMIT_S = 5.0  # a ball still on its crown after this long is held there for real
_SPHERE = int(mujoco.mjtGeom.mjGEOM_SPHERE)
_ROUND = frozenset(int(t) for t in (mujoco.mjtGeom.mjGEOM_SPHERE, mujoco.mjtGeom.mjGEOM_CAPSULE,
                                    mujoco.mjtGeom.mjGEOM_ELLIPSOID,
                                    mujoco.mjtGeom.mjGEOM_CYLINDER))
_CYLINDER = int(mujoco.mjtGeom.mjGEOM_CYLINDER)
_NEVER = int(mujoco.mjtSleepPolicy.mjSLEEP_NEVER)
_POLICIES = frozenset(int(p) for p in mujoco.mjtSleepPolicy.__members__.values())


class SleepGuard:
    """Watches one compiled model's single-sphere trees; build a new one after a compile."""

    def __init__(self, m: mujoco.MjModel) -> None:
        bodies = m.tree_bodyadr
        geoms = m.body_geomadr[bodies]
        one_geom = (m.tree_bodynum == 1) & (m.body_geomnum[bodies] == 1)
        lone_sphere = one_geom & (m.geom_type[np.where(one_geom, geoms, 0)] == _SPHERE) \
            if m.ngeom else one_geom  # a world of bodies without geoms has no sphere
        self._trees = np.flatnonzero(lone_sphere)
        self._geoms = geoms[self._trees]
        self._was_asleep = np.zeros(len(self._trees), dtype=bool)
        self._held: dict[int, tuple[int, int, float]] = {}  # tree -> (geom, policy, since)
        # Held for HOLD_LIMIT_S in vain -> whether it has slept since: free until it wakes.
        self._let_go: dict[int, bool] = {}

    def copy(self) -> SleepGuard:
        """A guard of the same model remembering the same (its model's arrays are shared:
        they are never written; the records are copied)."""
        twin: SleepGuard = object.__new__(SleepGuard)
        twin._trees, twin._geoms = self._trees, self._geoms
        twin._was_asleep = self._was_asleep.copy()
        twin._held, twin._let_go = dict(self._held), dict(self._let_go)
        return twin

    @property
    def held(self) -> list[int]:
        """Trees kept awake now (for tests and diagnostics)."""
        return sorted(self._held)

    def check(self, m: mujoco.MjModel, d: mujoco.MjData,
              writable: Callable[[], mujoco.MjModel] | None = None) -> None:
        """Wake balls that fell asleep on a crown; free those that have rolled off one.
        ``writable``: the model to write sleep policies into (a model shared with a fork is
        copied first, clone.own), called only when one changes."""
        own = writable if writable is not None else (lambda: m)
        if not len(self._trees) or not m.opt.enableflags & mujoco.mjtEnableBit.mjENBL_SLEEP:
            return
        up = _up(m)
        if up is None:
            return
        asleep = d.tree_asleep[self._trees] >= 0
        self._forget_woken(d)
        for i in np.flatnonzero(asleep & ~self._was_asleep):
            tree, geom = int(self._trees[i]), int(self._geoms[i])
            if tree not in self._held and tree not in self._let_go and \
                    on_a_crown(m, d, geom, up):
                m = own()
                self._held[tree] = (geom, int(m.tree_sleep_policy[tree]), float(d.time))
                m.tree_sleep_policy[tree] = _NEVER  # MuJoCo wakes it at the next step
        self._was_asleep = asleep
        for tree, (geom, _, since) in list(self._held.items()):
            if not 0.0 <= d.time - since < HOLD_LIMIT_S:  # (time may have been reset)
                self._release(own(), tree)
                self._let_go[tree] = False
            elif not on_a_crown(m, d, geom, up):
                self._release(own(), tree)

    def _forget_woken(self, d: mujoco.MjData) -> None:
        """A ball let go becomes a candidate again once it has slept and woken up."""
        for tree, slept in list(self._let_go.items()):
            if d.tree_asleep[tree] >= 0:
                self._let_go[tree] = True
            elif slept:
                del self._let_go[tree]

    def forget(self, m: mujoco.MjModel, trees: np.ndarray) -> None:
        """These trees left the world without a recompile (parked): free any held one."""
        for tree in map(int, trees):
            if tree in self._held:
                self._release(m, tree)
            self._let_go.pop(tree, None)

    def release_all(self, m: mujoco.MjModel) -> None:
        """Give every held ball its own sleep policy back (the guard is being switched off)."""
        for tree in list(self._held):
            self._release(m, tree)

    def records(self) -> dict[str, Any]:
        """What the guard remembers, as plain data (for a snapshot)."""
        return {"held": [[t, g, p, s] for t, (g, p, s) in self._held.items()],
                "let_go": [[t, slept] for t, slept in self._let_go.items()],
                "was_asleep": self._was_asleep.astype(np.uint8).tobytes()}

    def load(self, m: mujoco.MjModel, records: Any) -> None:
        """Take over a snapshot's records (``records``) on a fresh guard of the same model,
        holding its held balls awake again; InvalidArgumentError for malformed records."""
        if not isinstance(records, dict) or set(records) != {"held", "let_go", "was_asleep"}:
            raise InvalidArgumentError(f"snapshot.balance must be {{held, let_go, "
                                       f"was_asleep}}, got {brief(records)}")
        geoms = dict(zip(self._trees.tolist(), self._geoms.tolist(), strict=True))
        held = {self._tree(row, geoms): (row[1], row[2], row[3]) for row in
                _rows(records["held"], 4)}
        if any(geoms[t] != g or type(p) is not int or p not in _POLICIES or
               not isinstance(s, float) or not math.isfinite(s) for t, (g, p, s) in held.items()):
            raise InvalidArgumentError("snapshot.balance.held holds a ball that is not one")
        let_go = {self._tree(row, geoms): row[1] for row in _rows(records["let_go"], 2)}
        if not all(isinstance(slept, bool) for slept in let_go.values()):
            raise InvalidArgumentError("snapshot.balance.let_go must pair trees with bools")
        was = records["was_asleep"]
        if not isinstance(was, bytes) or len(was) != len(self._trees) or set(was) - {0, 1}:
            raise InvalidArgumentError(f"snapshot.balance.was_asleep must be {len(self._trees)}"
                                       f" bytes of 0 or 1, got {brief(was)}")
        self._held, self._let_go = held, let_go
        self._was_asleep = np.frombuffer(was, dtype=np.uint8).astype(bool)
        for tree in held:
            m.tree_sleep_policy[tree] = _NEVER

    @staticmethod
    def _tree(row: list[Any], geoms: dict[int, int]) -> int:
        tree = row[0]
        if type(tree) is not int or tree not in geoms:
            raise InvalidArgumentError(f"snapshot.balance names tree {brief(tree)}, which is "
                                       "no lone ball of this world")
        return tree

    def _release(self, m: mujoco.MjModel, tree: int) -> None:
        m.tree_sleep_policy[tree] = self._held.pop(tree)[1]


def _rows(value: Any, width: int) -> list[list[Any]]:
    if not isinstance(value, list) or not all(isinstance(r, list) and len(r) == width
                                              for r in value):
        raise InvalidArgumentError(f"snapshot.balance rows must be lists of {width}, got "
                                   f"{brief(value)}")
    return value


def _up(m: mujoco.MjModel) -> np.ndarray | None:
    norm = float(np.linalg.norm(m.opt.gravity))
    return None if norm == 0.0 else -np.asarray(m.opt.gravity) / norm


def on_a_crown(m: mujoco.MjModel, d: mujoco.MjData, geom: int, up: np.ndarray) -> bool:
    """Whether this sphere's weight rests on one fixed round geom, within CROWN_DEGREES of
    its top."""
    supports = list(_supports(m, d, geom, up))
    if len(supports) != 1:
        return False
    other, normal = supports[0]
    fixed = m.body_weldid[m.geom_bodyid[other]] == 0  # welded to the world: scenery
    return bool(fixed) and _is_round_there(m, d, other, normal) and \
        float(normal @ up) >= math.cos(math.radians(CROWN_DEGREES))


def _supports(m: mujoco.MjModel, d: mujoco.MjData, geom: int,
              up: np.ndarray) -> Iterator[tuple[int, np.ndarray]]:
    """(geom, unit normal towards the sphere) of each contact bearing the sphere's weight."""
    centre = d.geom_xpos[geom]
    radius = float(m.geom_size[geom, 0])
    fromto = np.empty(6)
    for other in _neighbours(m, d, geom, centre, radius):
        if mujoco.mj_geomDistance(m, d, geom, int(other), TOUCH, fromto) >= TOUCH:
            continue
        offset = centre - fromto[3:]
        length = float(np.linalg.norm(offset))
        if length == 0.0:
            continue
        normal = offset / length
        if float(normal @ up) >= SUPPORT_COSINE:
            yield int(other), normal


def _neighbours(m: mujoco.MjModel, d: mujoco.MjData, geom: int, centre: np.ndarray,
                radius: float) -> np.ndarray:
    """Geoms that can collide with this one and whose bounding spheres reach it."""
    collides = ((m.geom_contype & m.geom_conaffinity[geom]) != 0) | \
        ((m.geom_conaffinity & m.geom_contype[geom]) != 0)
    reach = np.linalg.norm(d.geom_xpos - centre, axis=1) <= radius + m.geom_rbound + TOUCH
    unbounded = m.geom_rbound == 0  # planes and height fields
    near = collides & (reach | unbounded) & (m.geom_bodyid != m.geom_bodyid[geom])
    return np.flatnonzero(near)


def _is_round_there(m: mujoco.MjModel, d: mujoco.MjData, geom: int, normal: np.ndarray) -> bool:
    """Whether the geom's surface is curved where this normal leaves it (a cylinder's caps
    are flat)."""
    kind = int(m.geom_type[geom])
    if kind != _CYLINDER:
        return kind in _ROUND
    axis = d.geom_xmat[geom].reshape(3, 3)[:, 2]
    return abs(float(normal @ axis)) < 0.5
