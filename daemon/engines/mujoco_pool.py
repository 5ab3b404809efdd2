"""Parked, pre-compiled MuJoCo bodies: spawning many bodies without a recompile.

A spawn that must recompile anyway also compiles spare twins of each new kind of body (shape,
size, static or dynamic, resolved material). A twin is *parked*: far below the world, its
collisions off (geom and body contype/conaffinity 0: MuJoCo's broadphase filters by the
body's), a dynamic one held against gravity by ``gravcomp`` 1 at zero velocity, so it never
moves and soon falls asleep. A later spawn of the same kind binds the names to parked bodies
(renamed in the spec), writes their states in one batch and switches their collisions on: no
recompile. Deleting a spawned body, or clearing the world, parks it again.

Parked bodies are no entities: the engine never gives out their ids, and nothing collides
with them. Pool lists hand out the lowest body ids first, so the same spawns after a clear bind
the same bodies (same ids, same order) and give the same numbers.

Cost: parked bodies are asleep (sleeping on, the default), yet MuJoCo still loops over them
in kinematics, constraint making and the broadphase: measured about 60 ns per parked body per
step (≈ 70 µs per step for 1,250 parked; ≈ 0.4 µs per body with sleeping off), hence
CAPACITY.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines import mujoco_spec as ms
from galton.daemon.engines import mujoco_state as mst
from galton.protocol import BodyGroup

_SLEEP = int(mujoco.mjtEnableBit.mjENBL_SLEEP)
# Where parked bodies wait: a wire pose [x y z qx qy qz qw].
PARK_AT = np.array([0.0, 0.0, -1000.0, 0.0, 0.0, 0.0, 1.0])
_PARK_WXYZ = mst.to_wxyz(PARK_AT[3:])
# A recompiling spawn of n bodies adds max(n // 4, SPARE_MIN) parked twins...
SPARE_MIN = 16
# ...as long as no more than CAPACITY bodies are parked in all.
CAPACITY = 2048
PREFIX = "galton.parked."  # parked bodies' names; no entity may take one

Key = tuple[Any, ...]


def key_of(group: BodyGroup, material: ms.Material) -> Key:
    """What makes two spawned bodies interchangeable once compiled."""
    return (group.shape, tuple(float(s) for s in group.size), bool(group.static), material)


class Pool:
    """Parked spec bodies by kind; see the module docstring."""

    def __init__(self) -> None:
        self._parked: dict[Key, list[Any]] = {}
        self._serial = 0

    def __len__(self) -> int:
        return sum(len(bodies) for bodies in self._parked.values())

    def available(self, key: Key) -> int:
        return len(self._parked.get(key, ()))

    def spares(self, count: int, coming: int = 0) -> int:
        """How many twins to compile beside a recompiling spawn of ``count`` bodies, when
        ``coming`` more are already planned for the same compile."""
        return max(0, min(max(count // 4, SPARE_MIN), CAPACITY - len(self) - coming))

    def _name(self) -> str:
        self._serial += 1
        return f"{PREFIX}{self._serial}"

    def add_spares(self, spec: mujoco.MjSpec, home: Any, group: BodyGroup,
                   material: ms.Material, key: Key, count: int) -> list[Any]:
        """Add ``count`` parked twins of this group's bodies to the spec (compiled later)."""
        if count <= 0:
            return []
        parked = BodyGroup(shape=group.shape, size=group.size,
                           names=[self._name() for _ in range(count)],
                           poses=np.tile(PARK_AT, (count, 1)), static=group.static)
        bodies = ms.add_group(spec, home, parked, material)
        for body in bodies:
            park_spec(body, group.static)
        self._parked.setdefault(key, []).extend(bodies)
        return bodies

    def take(self, key: Key, count: int) -> list[Any]:
        """The ``count`` parked bodies of this kind with the lowest ids, out of the pool."""
        bodies = sorted(self._parked[key], key=lambda body: body.id)
        self._parked[key] = bodies[count:]
        return bodies[:count]

    def split(self, entities: Sequence[Any]) -> tuple[list[Any], list[Any]]:
        """Which of these (soon former) entities the pool would park, while there is room
        (those still of their kind), and which must leave the spec; nothing changes yet."""
        room = CAPACITY - len(self)
        parked, removed = [], []
        for e in entities:
            fits = e.key is not None and len(parked) < room
            (parked if fits else removed).append(e)
        return parked, removed

    def park(self, entities: Sequence[Any]) -> None:
        """Park the bodies of these former entities (as ``split`` chose): renamed, collisions
        off, at rest far below; their arrays are parked by ``park_arrays``."""
        for e in entities:
            e.body.name = self._name()
            park_spec(e.body, e.static)
            self._parked.setdefault(e.key, []).append(e.body)

    def snapshot(self) -> tuple[int, dict[Key, list[Any]]]:
        """The pool as it is, for ``restore`` if what follows fails."""
        return self._serial, {key: list(bodies) for key, bodies in self._parked.items()}

    def restore(self, snapshot: tuple[int, dict[Key, list[Any]]]) -> None:
        self._serial, parked = snapshot
        self._parked = {key: list(bodies) for key, bodies in parked.items()}

    def clear(self) -> None:
        self._parked.clear()


# -- the spec: what a recompile will keep -------------------------------------------------
def park_spec(body: Any, static: bool) -> None:
    body.pos = PARK_AT[:3]
    body.quat = _PARK_WXYZ
    body.gravcomp = 0.0 if static else 1.0
    geom = body.first_geom()
    geom.contype = geom.conaffinity = 0


def bind_spec(bodies: Sequence[Any], names: Sequence[str], poses: np.ndarray) -> None:
    quats = mst.to_wxyz(poses[:, 3:])
    for row, (body, name) in enumerate(zip(bodies, names, strict=True)):
        body.name = name
        body.pos = poses[row, :3]
        body.quat = quats[row]
        body.gravcomp = 0.0
        geom = body.first_geom()
        geom.contype = geom.conaffinity = 1


# -- the compiled model and its data: what the next step sees -----------------------------
def _collide(m: mujoco.MjModel, ids: np.ndarray, on: int) -> None:
    m.body_contype[ids] = on
    m.body_conaffinity[ids] = on
    gids = m.body_geomadr[ids]
    m.geom_contype[gids] = on
    m.geom_conaffinity[gids] = on


def _place(m: mujoco.MjModel, d: mujoco.MjData, index: mst.StateIndex, ids: np.ndarray,
           poses: np.ndarray) -> None:
    """Pose bodies at rest: static ones in the model, free ones in qpos (and qpos0)."""
    static = index.kind[ids] == mst.STATIC
    if static.any():
        m.body_pos[ids[static]] = poses[static, :3]
        m.body_quat[ids[static]] = mst.to_wxyz(poses[static, 3:])
    free = ids[index.kind[ids] == mst.FREE]
    if len(free):
        rows = poses[index.kind[ids] == mst.FREE]
        mst.write_free_poses(d, index, free, rows)
        qadr = index.qadr[free][:, None] + mst.POSE
        m.qpos0[qadr] = d.qpos[qadr]
        vadr = index.vadr[free][:, None] + mst.TWIST
        d.qvel[vadr] = 0.0
        d.qacc_warmstart[vadr] = 0.0
        m.body_gravcomp[free] = 0.0


def park_arrays(m: mujoco.MjModel, d: mujoco.MjData, index: mst.StateIndex,
                ids: np.ndarray) -> None:
    """Park compiled bodies: collisions off, at rest far below, held against gravity."""
    _collide(m, ids, 0)
    _place(m, d, index, ids, np.tile(PARK_AT, (len(ids), 1)))
    m.body_gravcomp[ids[index.kind[ids] == mst.FREE]] = 1.0


def bind_arrays(m: mujoco.MjModel, d: mujoco.MjData, index: mst.StateIndex, ids: np.ndarray,
                poses: np.ndarray) -> None:
    """Release parked bodies at these poses, at rest, collisions on (wake them after)."""
    _place(m, d, index, ids, poses)
    _collide(m, ids, 1)


def refresh(m: mujoco.MjModel, d: mujoco.MjData) -> None:
    """After releasing bodies: wake every tree and recompute positions (MuJoCo does not
    recompute a static body's pose at the next step by itself), keeping the state."""
    asleep = m.opt.enableflags & _SLEEP
    m.opt.enableflags &= ~_SLEEP
    mujoco.mj_forward(m, d)
    m.opt.enableflags |= asleep
