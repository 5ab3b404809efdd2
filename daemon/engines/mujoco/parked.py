"""Spawned bodies in the MuJoCo spec: added in batches, parked for reuse, removed.

Adding: MuJoCo walks the whole spec after every body, joint or geom added to it, and finds a
body by name by walking it too until the next compile, so n bodies added one by one to a spec
of N cost O(n·N) (8,000 spheres took 0.9 s, 16,000 four times that). ``Additions`` adds a
small group directly; a group of ATTACH_MIN or more is built in specs of CHUNK bodies, attached
into blocks of BLOCK bodies, each attached to the world (an attach walks the spec it goes into
once, about 1 µs per element) under temporary names; they are found by those names once
compiled (MuJoCo indexes names at compile), then renamed and gathered in one frame. The
building specs are ``Builders``, used again and again.

Parking: spawning many bodies without a recompile.

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
from typing import Any, NamedTuple

import mujoco
import numpy as np

from galton.daemon.engines.geometry import DENSITY
from galton.daemon.engines.mujoco import body_extras
from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import params as mparams
from galton.daemon.engines.mujoco import state as mst
from galton.protocol import BodyGroup, ResourceLimitError

_SLEEP = int(mujoco.mjtEnableBit.mjENBL_SLEEP)
# Where parked bodies wait: a wire pose [x y z qx qy qz qw].
PARK_AT = np.array([0.0, 0.0, -1000.0, 0.0, 0.0, 0.0, 1.0])
_PARK_WXYZ = mst.to_wxyz(PARK_AT[3:])
# A recompiling spawn of n bodies adds max(n // 4, SPARE_MIN) parked twins, at most
# SPARE_MAX (MuJoCo's compile time grows with the square of the free bodies: 2,048 spares
# beside 10,000 spheres made it 45 % slower)...
SPARE_MIN = 16
SPARE_MAX = 512
# ...as long as no more than CAPACITY bodies are parked in all.
CAPACITY = 2048
PREFIX = "galton.parked."  # parked bodies' names; no entity may take one

Key = tuple[Any, ...]


def key_of(group: BodyGroup, material: ms.Material) -> Key | None:
    """What makes two spawned bodies interchangeable once compiled; None for bodies never
    parked: meshes (each group its own mesh asset) and bodies with their own inertia."""
    if group.vertices is not None or group.inertia is not None:
        return None
    return (group.shape, tuple(float(s) for s in group.size), bool(group.static), material)


class Planned(NamedTuple):
    """A group a spawn compiles: its resolved material, its kind, its spare twins."""

    group: BodyGroup
    material: ms.Material
    key: Key | None
    spares: int


class ParkedBodies:
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
        return max(0, min(max(count // 4, SPARE_MIN), SPARE_MAX, CAPACITY - len(self) - coming))

    def _name(self) -> str:
        self._serial += 1
        return f"{PREFIX}{self._serial}"

    def plan(self, groups: Sequence[BodyGroup], values: dict[str, Any], nbody: int,
             entities: int, nfree: int) -> tuple[list[tuple[BodyGroup, Key]], list[Planned]]:
        """Which groups of a spawn take parked bodies, and which are compiled, with how many
        spares, into a world of ``nbody`` bodies (``nfree`` of them free); ResourceLimitError
        for a world MuJoCo cannot hold, or one whose compile would take minutes, before
        anything is done."""
        pooled, compiled = [], []
        wanted: dict[Key, int] = {}
        for group in groups:
            material = ms.material(group, values)
            key = key_of(group, material)
            if key is not None and self.available(key) >= wanted.get(key, 0) + len(group):
                wanted[key] = wanted.get(key, 0) + len(group)
                pooled.append((group, key))
            else:
                nbody += len(group)
                compiled.append(Planned(group, material, key, 0))
        if nbody > mparams.MAX_BODIES:
            raise ResourceLimitError(
                f"MuJoCo holds at most {mparams.MAX_BODIES} bodies in one world (its broadphase "
                f"numbers them with 16 bits); this spawn would make {nbody} (the world has "
                f"{entities} entities and {len(self)} parked bodies)",
                {"limit": "mujoco_bodies", "max": mparams.MAX_BODIES, "count": nbody})
        free_room = values["mujoco.max_free_bodies"] - nfree
        if compiled:
            free_room -= sum(len(p.group) for p in compiled if not p.group.static)
            check_free_bodies(values["mujoco.max_free_bodies"] - free_room,
                              values["mujoco.max_free_bodies"])
        spares = 0
        for i, planned in enumerate(compiled):
            if planned.key is None:
                continue  # never parked: no spare twins
            count = min(self.spares(len(planned.group), spares),
                        mparams.MAX_BODIES - nbody - spares)
            if not planned.group.static:  # spare twins of moving bodies are free bodies too
                count = min(count, free_room)
                free_room -= count
            compiled[i] = planned._replace(spares=count)
            spares += count
        return pooled, compiled

    def spare_group(self, group: BodyGroup, count: int) -> BodyGroup:
        """``count`` parked twins of this group's bodies, named, to add beside it."""
        return BodyGroup(shape=group.shape, size=group.size,
                         names=[self._name() for _ in range(count)],
                         poses=np.tile(PARK_AT, (count, 1)), static=group.static)

    def adopt(self, key: Key, bodies: Sequence[Any]) -> None:
        """Take compiled spare twins (parked by ``park_spec`` as they were made)."""
        self._parked.setdefault(key, []).extend(bodies)

    def take(self, key: Key, count: int) -> list[Any]:
        """The ``count`` parked bodies of this kind with the lowest ids, out of the pool."""
        bodies = sorted(self._parked[key], key=lambda body: body.id)
        self._parked[key] = bodies[count:]
        return bodies[:count]

    def split(self, entities: Sequence[Any]) -> tuple[list[Any], list[Any]]:
        """Which of these (soon former) entities the pool would park, while there is room
        (those still of their kind), and which must leave the spec; nothing changes yet."""
        room = CAPACITY - len(self)
        parked: list[Any] = []
        removed: list[Any] = []
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
ATTACH_MIN = 64  # groups this large are built apart and attached (see the module docstring)
CHUNK = 512  # bodies built in one spec...
BLOCK = 8192  # ...and chunks attached into one spec, which is attached to the world
_TEMPORARY = "\x01"  # attached bodies' names begin so until renamed: no entity's name can


class Builders:
    """The specs big groups are built in, one set per world, emptied and used again: MuJoCo
    keeps every spec ever attached to another alive, and each slowed later attaches (fresh
    ones each time: 0.25 MB and 0.2 ms more per spawn, for good)."""

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """New, empty specs (the old ones may hold half a group after a failure)."""
        self.block = mujoco.MjSpec()
        self.block.copy_during_attach = True
        self.chunks = [mujoco.MjSpec() for _ in range(BLOCK // CHUNK)]


class Additions:
    """Bodies added to a spec for one compile: ``add`` groups, compile, then ``bodies``
    (or ``undo`` if the compile failed)."""

    def __init__(self, spec: mujoco.MjSpec, builders: Builders) -> None:
        self.mj_spec, self.builders = spec, builders
        self._groups: list[tuple[BodyGroup, list[Any] | None]] = []  # None: attached
        self._frames: list[Any] = []
        self._homes: list[Any] = []  # a frame per attached group, made before the compile
        self._direct: list[Any] = []
        self._meshes: list[str] = []  # mesh assets' names
        self._attached = 0

    def add(self, group: BodyGroup, material: ms.Material, parked: bool = False) -> None:
        """Add one body per name; ``parked`` ones are parked (``park_spec``) as they are made.

        A dynamic body gets a free joint. A static one is a jointless child of the world, not
        a mocap body: MuJoCo counts mocap bodies as always awake and wakes every sleeping ball
        touching one, so a board of mocap bodies would never let its piles sleep. A static
        body still moves without a compile: its pose lives in the model (body_pos, body_quat).
        """
        if len(group) < ATTACH_MIN or group.vertices is not None:
            mesh = body_extras.add_mesh(self.mj_spec, group)
            if mesh is not None:
                self._meshes.append(mesh)
            bodies = _add_bodies(self.mj_spec.worldbody, group, material, range(len(group)),
                                 parked, group.names, mesh)
            self._direct += bodies
            self._groups.append((group, bodies))
            return
        block, chunks = self.builders.block, self.builders.chunks
        self._homes.append(self.mj_spec.worldbody.add_frame())
        try:
            for start in range(0, len(group), BLOCK):
                for chunk, first in zip(chunks, range(start, min(start + BLOCK, len(group)),
                                                      CHUNK), strict=False):
                    rows = range(first, min(first + CHUNK, len(group)))
                    _add_bodies(chunk.worldbody, group, material, rows, parked,
                                [str(self._attached + row - rows.start) for row in rows])
                    self._attached += len(rows)
                    _attach(block, chunk, block.worldbody.add_frame())
                self._frames.append(self.mj_spec.worldbody.add_frame())
                _attach(self.mj_spec, block, self._frames[-1])
        except BaseException:
            self.builders.reset()
            raise
        self._groups.append((group, None))

    def undo(self) -> None:
        """Take every added body (and mesh asset) out of the spec again."""
        _delete(self.mj_spec, self._direct, [*self._frames, *self._homes])
        for name in self._meshes:
            self.mj_spec.delete(self.mj_spec.mesh(name))

    def bodies(self) -> list[list[Any]]:
        """Once compiled: each added group's bodies, named, each attached group gathered in
        a frame of its own. All are found before any is renamed: a rename may drop MuJoCo's
        index of names. The frames they leave empty are ``empty_frames``: a delete costs a walk of
        the spec (0.6 s at 60,000 bodies, 1.8 s right after a compile), so they go with the
        next bodies deleted. (The groups' frames were made before the compile: adding any
        element to a spec drops the ids of its compiled bodies.)

        One frame per group, not one for all: MJCF writes a frame's bodies together, where
        its first body is, while a compile keeps the bodies' order; a frame shared by groups
        spawned apart would make a snapshot's MJCF compile its bodies in another order than
        the world's (whose arrays the snapshot holds by position)."""
        found = iter([self.mj_spec.body(f"{_TEMPORARY * 2}{i}") for i in range(self._attached)])
        homes = iter(self._homes)
        out = []
        for group, bodies in self._groups:
            if bodies is None:
                bodies = [next(found) for _ in group.names]
                frame = next(homes)
                for body, name in zip(bodies, group.names, strict=True):
                    body.name = name
                    body.set_frame(frame)
            out.append(bodies)
        return out

    @property
    def empty_frames(self) -> list[Any]:
        return self._frames


def _attach(spec: mujoco.MjSpec, child: mujoco.MjSpec, frame: Any) -> None:
    """Attach a child spec's bodies to a frame of the spec's world, prefixed _TEMPORARY.

    An attach also copies the child's defaults as a class of their own, which no element
    names (theirs say "main"), and keeps the child alive: both are dropped.
    """
    spec.attach(child, prefix=_TEMPORARY, frame=frame)
    spec.delete(spec.find_default(f"{_TEMPORARY}main"))
    _delete(child, [], child.worldbody.frames)  # they hold every body once attached


def _geom(group: BodyGroup, material: ms.Material, mesh: str | None = None
          ) -> dict[str, Any]:
    geom: dict[str, Any] = {
        "type": ms.GEOM_TYPES[group.shape], "size": ms.geom_size(group.shape, group.size),
        "friction": [material.friction, *material.spin], "condim": material.condim,
        "solref": list(material.solref), "solimp": list(material.solimp),
        "priority": ms.STATIC_PRIORITY if group.static else 0}
    if material.rgba is not None:
        geom["rgba"] = list(material.rgba)
    if mesh is not None:
        geom["meshname"] = mesh
    if material.mass is not None and not group.static:
        geom["mass"] = material.mass
    else:
        geom["density"] = DENSITY
    return geom


def _add_bodies(parent: Any, group: BodyGroup, material: ms.Material, rows: range,
                parked: bool, names: Sequence[str], mesh: str | None = None) -> list[Any]:
    geom = _geom(group, material, mesh)
    inertial = body_extras.inertial(group, material.mass)
    poses = np.asarray(group.poses, dtype=float)[rows.start:rows.stop]
    quats = mst.to_wxyz(poses[:, 3:7])
    bodies = []
    for i, name in enumerate(names):
        body = parent.add_body(name=name, pos=poses[i, :3], quat=quats[i], **inertial)
        bodies.append(body)
        if not group.static:
            body.add_freejoint()
        body.add_geom(**geom)
        if parked:
            park_spec(body, group.static)
    return bodies


def _delete(spec: mujoco.MjSpec, bodies: Sequence[Any], frames: Sequence[Any]) -> None:
    """Delete bodies and frames (with what they hold) in one go: gathered under one frame,
    then it deleted. (Deleting them one at a time walks the whole spec each time: 12 ms per
    body at 1,000 bodies.)"""
    if not bodies and not frames:
        return
    bin_ = spec.worldbody.add_frame()
    for element in (*bodies, *frames):
        element.set_frame(bin_)
    spec.delete(bin_)


def remove_bodies(spec: mujoco.MjSpec, bodies: Sequence[Any],
                  empty_frames: Sequence[Any] = ()) -> None:
    """Delete these top-level bodies (and their subtrees) from the spec in one go, with
    these empty frames (``Additions.empty_frames``)."""
    _delete(spec, bodies, empty_frames)


def remove_frame(spec: mujoco.MjSpec, frame: Any) -> None:
    """Delete a frame of the world with the bodies in it (MuJoCo drops what used them)."""
    _delete(spec, [], [frame])


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


def check_free_bodies(count: int, limit: int) -> None:
    """Refuse a compile with more free bodies than ``mujoco.max_free_bodies``."""
    if count > limit:
        raise ResourceLimitError(
            f"this request would compile a MuJoCo world of {count} moving bodies; the "
            f"parameter mujoco.max_free_bodies allows {limit} (MuJoCo's compile is quadratic "
            "in them: 10,000 take about 12 s)",
            {"limit": "mujoco.max_free_bodies", "max": limit, "count": count})
