"""MuJoCo building blocks written into the ``MjSpec`` (hence the name): the restitution
mapping, the options, materials, geom sizes, the arena, MJCF parsing.

Kept apart from ``engine`` so the engine reads as the Engine contract and this module
as the MuJoCo vocabulary it is written in.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco.params import CONES, INTEGRATORS, SOLVERS
from galton.protocol import BodyGroup, InvalidArgumentError

log = logging.getLogger("galton.daemon.mujoco")

GEOM_TYPES: dict[str, int] = {
    "sphere": mujoco.mjtGeom.mjGEOM_SPHERE,
    "box": mujoco.mjtGeom.mjGEOM_BOX,
    "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
    "capsule": mujoco.mjtGeom.mjGEOM_CAPSULE,
    "plane": mujoco.mjtGeom.mjGEOM_PLANE,
    "mesh": mujoco.mjtGeom.mjGEOM_MESH,  # collides as its convex hull
}
# Bodies given no mass get MuJoCo's default density, water's.
# A contact between geoms of different priority takes the higher one's friction, solref and
# solimp (MuJoCo's rule); static bodies outrank moving ones, so a ball on a pin feels the
# pin's surface and two balls their own (see docs/PHYSICS.md).
STATIC_PRIORITY = 1
# The smallest damping ratio a restitution may map to, whatever the step allows.
MIN_DAMPRATIO = 0.01
# The arena beyond the pair buffers (see arena_bytes).
ARENA_BASE = 16 << 20
ARENA_PER_BODY = 8 << 10
ARENA_PER_DOF = 8 << 10
ARENA_CAP = 4 << 30
# MuJoCo's warnings that mean the state blew up during a step.
DIVERGENCE_WARNINGS = np.array([int(w) for w in (
    mujoco.mjtWarning.mjWARN_BADQPOS, mujoco.mjtWarning.mjWARN_BADQVEL,
    mujoco.mjtWarning.mjWARN_BADQACC)])




def route_warnings() -> None:
    """Send MuJoCo's warnings to logging rather than to stdout and ./MUJOCO_LOG.TXT.

    The handler is process-wide; one already set by someone else is left alone.
    """
    if mujoco.get_mju_user_warning() is None:
        mujoco.set_mju_user_warning(_log_warning)


def _log_warning(message: str) -> None:
    log.warning("MuJoCo: %s", message)


def damping_floor(values: dict[str, Any]) -> float:
    """The smallest damping ratio the current step integrates stably.

    MuJoCo's contact spring has angular frequency 1 / (dmax·timeconst·dampratio), so a low
    damping ratio stiffens the spring; measured drop tests gain energy once that frequency
    times the step passes about 1 (timeconst is at least 2 steps, MuJoCo's own refsafe).
    """
    timestep = values["timestep"]
    timeconst = max(values["mujoco.solref"][0], 2 * timestep)
    return float(max(MIN_DAMPRATIO, timestep / (values["mujoco.solimp"][1] * timeconst)))


def damping_ratio(restitution: float, floor: float) -> float:
    """The solref damping ratio ζ giving a nominal restitution e to a contact.

    A damped spring-mass contact bounces back with e = exp(-ζπ / sqrt(1 - ζ²)); inverted,
    ζ = L / sqrt(π² + L²) with L = -ln e. e = 0 gives ζ = 1 (critically damped); ζ is clamped
    to ``floor`` (see damping_floor), so the highest reachable e depends on the step: about
    0.72 at MuJoCo's defaults (2 ms, timeconst 0.02 s). Measured bounces track the formula
    within ±0.05 for ζ in 0.1..0.3 but exceed it when damped (ζ = 1 still bounces ≈ 0.12,
    MuJoCo's soft impedance). A contact averages its two geoms' solref (solmix 1), so both
    bodies need the restitution for the full effect.
    """
    if restitution <= 0:
        return 1.0
    decay = -math.log(restitution)
    return max(floor, decay / math.sqrt(math.pi**2 + decay**2))


def contact_solref(restitution: float, values: dict[str, Any]) -> tuple[float, float]:
    """solref of a geom: mujoco.solref as given for e = 0, its damping replaced for e > 0."""
    timeconst, dampratio = values["mujoco.solref"]
    if restitution <= 0:
        return (timeconst, dampratio)
    return (timeconst, damping_ratio(restitution, damping_floor(values)))


def spin_friction(values: dict[str, Any]) -> tuple[float, float]:
    return (values["mujoco.torsional_friction"], values["mujoco.rolling_friction"])


def write_options(option: Any, values: dict[str, Any]) -> None:
    """Copy the global parameters onto an mjOption (the spec's or the compiled model's)."""
    option.timestep = values["timestep"]
    option.gravity = values["gravity"]
    option.iterations = values["solver_iterations"]
    option.ls_iterations = values["mujoco.ls_iterations"]
    option.tolerance = values["mujoco.tolerance"]
    option.noslip_iterations = values["mujoco.noslip_iterations"]
    option.solver = SOLVERS[values["mujoco.solver"]]
    option.cone = CONES[values["mujoco.cone"]]
    option.integrator = INTEGRATORS[values["mujoco.integrator"]]
    option.disableflags |= mujoco.mjtDisableBit.mjDSBL_AUTORESET
    tolerance = values["mujoco.sleep_tolerance"]
    if tolerance > 0:
        option.sleep_tolerance = tolerance
        option.enableflags |= mujoco.mjtEnableBit.mjENBL_SLEEP
    else:
        option.enableflags &= ~int(mujoco.mjtEnableBit.mjENBL_SLEEP)


# -- bodies ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Material:
    """Per-geom values shared by a spawned group, resolved once for the whole group."""

    friction: float
    spin: tuple[float, float]  # torsional and rolling friction, m
    condim: int
    solref: tuple[float, float]
    solimp: tuple[float, ...]
    rgba: tuple[float, float, float, float] | None
    mass: float | None


def default_surface(static: bool, v: dict[str, Any]) -> tuple[float, float]:
    """The friction and restitution a body given none gets: the scenery has its own."""
    if static:
        return v["default_static_friction"], v["default_static_restitution"]
    return v["default_friction"], v["default_restitution"]


def material(group: BodyGroup, v: dict[str, Any]) -> Material:
    """A group's per-geom values, the defaults where it gives none."""
    friction, restitution = default_surface(group.static, v)
    if group.friction is not None:
        friction = group.friction
    if group.restitution is not None:
        restitution = group.restitution
    return Material(friction=friction, spin=spin_friction(v), condim=v["mujoco.condim"],
                    solref=contact_solref(restitution, v), solimp=tuple(v["mujoco.solimp"]),
                    rgba=group.rgba, mass=group.mass)


def write_contacts(m: mujoco.MjModel, geoms: list[Any], gids: np.ndarray, v: dict[str, Any],
                   friction: float | None, restitution: float | None, spawned: bool) -> None:
    """One entity's contact values into the model (these geom ids) and its spec geoms."""
    solimp, spin = v["mujoco.solimp"], spin_friction(v)
    solref = None if restitution is None else contact_solref(restitution, v)
    if friction is not None:
        m.geom_friction[gids, 0] = friction
    if solref is not None:
        m.geom_solref[gids] = solref
    if spawned:
        m.geom_solimp[gids] = solimp
        m.geom_friction[gids, 1:] = spin
        m.geom_condim[gids] = v["mujoco.condim"]
    for geom in geoms:
        if friction is not None:
            geom.friction[0] = friction
        if solref is not None:
            geom.solref = solref
        if spawned:
            geom.solimp = solimp
            geom.friction[1:] = spin
            geom.condim = v["mujoco.condim"]


def geom_size(shape: str, size: tuple[float, ...]) -> list[float]:
    """MuJoCo's size triple; a plane's third number is only its rendered grid spacing."""
    if shape == "sphere":
        return [size[0], 0.0, 0.0]
    if shape in ("cylinder", "capsule"):
        return [size[0], size[1], 0.0]
    if shape == "plane":
        return [size[0], size[1], max(0.01, min(size) / 10)]
    if shape == "mesh":
        return [0.0, 0.0, 0.0]  # the compiler sizes a mesh geom from its mesh
    return list(size)


def set_values(element: Any, **values: Any) -> list[tuple[Any, str, Any]]:
    """Set a spec element's attributes; return (element, attribute, old value) to undo it."""
    undo = [(element, name, np.array(getattr(element, name), copy=True)
             if isinstance(getattr(element, name), np.ndarray) else getattr(element, name))
            for name in values]
    for name, value in values.items():
        setattr(element, name, value)
    return undo


def arena_bytes(nbody: int, nv: int) -> int:
    """The MjData arena a world of this size needs (the spec's ``memory``).

    Every step, mj_collision and mj_broadphase each take nbody²/2 ints from the arena for
    candidate pairs, however few there are: 4·nbody² bytes. MuJoCo's own default ignores
    them (a few thousand static bodies overflowed it at the first step) and grows with nv²
    instead (40·nv² bytes: 6 GB for 2,000 free spheres, "Could not allocate memory" past
    about 4,000). What the solver needs beside the pairs: CG and PGS about 11 and 17 kB per
    ball in a settled pile of 2,000; Newton factors each island, up to 4·nv² bytes. So: the
    pairs, plus the larger of a linear budget and MuJoCo's default capped at ARENA_CAP. It is
    address space: only the pages used are ever touched.
    """
    linear = ARENA_BASE + ARENA_PER_BODY * nbody + ARENA_PER_DOF * nv
    mujoco_default = 40 * (500 + nv) ** 2
    return 4 * nbody * nbody + max(linear, min(mujoco_default, ARENA_CAP))


# -- loaded models -----------------------------------------------------------------------
def parse_mjcf(text: str | None, path: str | None) -> mujoco.MjSpec:
    """Parse an MJCF model, from its text when given (the path is then for information);
    see ``ready_tops`` for what its top-level bodies need."""
    if text is None and path is None:
        raise InvalidArgumentError("give the MJCF model as text or a path")
    try:
        child = mujoco.MjSpec.from_string(text) if text is not None \
            else mujoco.MjSpec.from_file(str(path))
    except ValueError as exc:
        raise InvalidArgumentError(f"the MJCF model does not parse: {exc}") from exc
    return child


def ready_tops(child: mujoco.MjSpec, fmt: str) -> None:
    """Refuse geoms of the world itself; name the top-level bodies, and make jointless ones
    mocap (a fixed base the World can still move)."""
    if child.worldbody.geoms:
        raise InvalidArgumentError(
            f"the {fmt.upper()} model has geoms directly in its world; they would belong "
            "to no entity: put them in a body (or spawn a plane for the ground)")
    for i, body in enumerate(child.worldbody.bodies):
        body.name = body.name or f"body{i}"
        if not body.joints and not body.mocap:
            body.mocap = True


def model_names(child: mujoco.MjSpec, prefix: str, rename: Callable[[str], str] = str
                ) -> tuple[list[str], list[tuple[str, ...]]]:
    """The names a parsed model's bodies take once attached with this prefix (and renamed):
    its top-level bodies (the roots), and the other bodies of each (its links)."""
    tops = child.worldbody.bodies
    parts = [tuple(prefix + rename(b.name) for b in top.find_all(mujoco.mjtObj.mjOBJ_BODY))
             for top in tops]
    return [prefix + rename(top.name) for top in tops], parts
