"""The PyBullet engine's states, as functions of the engine: reading and setting the
entities' poses and twists (link frames, not PyBullet's centres of mass:
frames.py) and the divergence check.

PyBullet has no batch getter: states are read one call per body and per quantity, the
nested tuples flattened straight into numpy, the cheapest way measured.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from galton.daemon.engines.pybullet import articulated, rebuild
from galton.daemon.engines.pybullet.frames import com_to_frame
from galton.protocol.vocabulary import POSE_WIDTH, TWIST_WIDTH

if TYPE_CHECKING:
    from galton.daemon.engines.pybullet.engine import PybulletEngine


def get_states(engine: PybulletEngine, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Link frames, not PyBullet's centres of mass (frames.py)."""
    links = engine.robots.links
    if links and any(name in links for name in names):
        return states_with_links(engine, names)
    poses, twists = read(engine, [b.uid for b in engine.lookup(names)])
    if engine.held:  # right after a rebuild: the states as they were before it
        rebuild.report_held(engine.held, names, poses, twists)
    frames = engine.frames
    if frames:
        rows = [k for k, name in enumerate(names) if name in frames]
        if rows:
            some_poses, some_twists = poses[rows], twists[rows]
            com_to_frame(some_poses, some_twists, [frames[names[k]] for k in rows])
            poses[rows], twists[rows] = some_poses, some_twists
    return poses, twists


def states_with_links(engine: PybulletEngine, names: Sequence[str]
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Models' links from their articulation, every other entity as ``get_states`` reads it."""
    links = engine.robots.links
    rows = [k for k, name in enumerate(names) if name in links]
    others = [k for k, name in enumerate(names) if name not in links]
    poses, twists = np.zeros((len(names), POSE_WIDTH)), np.zeros((len(names), TWIST_WIDTH))
    if others:
        poses[others], twists[others] = engine.get_states([names[k] for k in others])
    articulated.put_link_states(engine, names, rows, poses, twists)
    return poses, twists


def read(engine: PybulletEngine, ids: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """The bodies' base poses and twists, one PyBullet call per body and per quantity."""
    n, flat = len(ids), itertools.chain.from_iterable
    poses = np.fromiter(flat(flat(map(engine.get_pose, ids))), float, n * POSE_WIDTH)
    twists = np.fromiter(flat(flat(map(engine.get_velocity, ids))), float, n * TWIST_WIDTH)
    return poses.reshape(n, POSE_WIDTH), twists.reshape(n, TWIST_WIDTH)


def set_states(engine: PybulletEngine, names: Sequence[str], poses: np.ndarray | None,
               twists: np.ndarray | None) -> None:
    """A pose alone keeps each body's twist, a twist alone its pose, as on every engine:
    resetBasePositionAndOrientation zeroes the twist, so it is read first and set again."""
    ids = [b.uid for b in engine.lookup(names)]
    if engine.held:
        rebuild.release_held(engine.held, names, poses is not None, twists is not None)
    if engine.frames and any(name in engine.frames for name in names):
        poses, twists = articulated.to_centres(engine, names, poses, twists)
    if poses is not None:
        rows = np.asarray(poses, dtype=float).tolist()
        if twists is None:
            twists = read(engine, ids)[1]
        for uid, pose in zip(ids, rows, strict=True):
            engine.reset_pose(uid, pose[:3], pose[3:])
        engine.given.update(zip(names, rows, strict=True))
    if twists is not None:
        for uid, twist in zip(ids, np.asarray(twists, dtype=float).tolist(), strict=True):
            engine.reset_velocity(uid, twist[:3], twist[3:])


def state_within(engine: PybulletEngine, max_position: float, max_speed: float) -> bool:
    """Static bodies cannot move in a step, so only the others are read: a board's
    hundreds of pins cost nothing here. Bullet itself reports no divergence: a ball at
    x = 4e299 is finite, and falls on there as if nothing were wrong."""
    moving = [b.uid for b in engine.bodies.values() if not b.static]
    if not articulated.joints_finite(engine):
        return False
    if not moving:
        return True
    poses, twists = read(engine, moving)
    return bool(np.isfinite(poses).all() and np.isfinite(twists).all()
                and np.abs(poses[:, :3]).max() <= max_position
                and np.abs(twists).max() <= max_speed)


class PoseReader:
    """A state stream's reader of fixed names: base poses only (no velocities), the bodies
    looked up once, again after each rebuild. Models' links, bodies whose frame is not their
    centre of mass, and states held over a rebuild read as get_states reads them."""

    def __init__(self, engine: PybulletEngine, names: Sequence[str]) -> None:
        self.engine = engine
        self.names = list(names)
        self.rebuilds = -1
        self.plain = False
        self.ids: list[int] = []

    def __call__(self) -> np.ndarray:
        engine = self.engine
        if self.rebuilds != engine.rebuilds:
            self._locate()
        if not self.plain or engine.held:
            return get_states(engine, self.names)[0]
        n, flat = len(self.ids), itertools.chain.from_iterable
        poses = np.fromiter(flat(flat(map(engine.get_pose, self.ids))), float, n * POSE_WIDTH)
        return poses.reshape(n, POSE_WIDTH)

    def _locate(self) -> None:
        engine = self.engine
        self.rebuilds = engine.rebuilds
        self.plain = not any(n in engine.robots.links or n in engine.frames
                             for n in self.names)
        self.ids = [b.uid for b in engine.lookup(self.names)] if self.plain else []
