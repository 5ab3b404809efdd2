"""The MuJoCo engine's parameters: name, default, unit, meaning, check and source of each
(docs/ENGINES.md tables them), and the solver choices they name."""

from __future__ import annotations

from typing import Any

import mujoco

from galton.daemon.engines.params import (
    ParamSpec,
    choice,
    flag,
    integer,
    number,
    shared,
    vector,
    with_sources,
)
from galton.protocol import InvalidArgumentError
from galton.protocol.errors import brief

# MuJoCo refuses a model of more bodies (the world body and parked ones included): its
# broadphase numbers bodies with 16 bits.
MAX_BODIES = 65_533
SOLVERS = {"newton": mujoco.mjtSolver.mjSOL_NEWTON, "cg": mujoco.mjtSolver.mjSOL_CG,
           "pgs": mujoco.mjtSolver.mjSOL_PGS}
CONES = {"pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL, "elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC}
INTEGRATORS = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicit": mujoco.mjtIntegrator.mjINT_IMPLICIT,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "rk4": mujoco.mjtIntegrator.mjINT_RK4}


def _solref(value: Any, where: str) -> tuple[float, ...]:
    timeconst, dampratio = vector(2, 0.0, 10.0)(value, where)
    if timeconst <= 0 or dampratio <= 0:
        raise InvalidArgumentError(f"{where} must be [timeconst > 0 s, dampratio > 0], got "
                                   f"{brief(value)}")
    return (timeconst, dampratio)


def _solimp(value: Any, where: str) -> tuple[float, ...]:
    dmin, dmax, width, mid, power = vector(5, 0.0, 1e3)(value, where)
    if not (0 < dmin <= dmax < 1 and width > 0 and 0 < mid < 1 and power >= 1):
        raise InvalidArgumentError(
            f"{where} must be [dmin, dmax, width, midpoint, power] with 0 < dmin <= dmax < 1, "
            f"width > 0, 0 < midpoint < 1, power >= 1; got {brief(value)}")
    return (dmin, dmax, width, mid, power)


def _condim(value: Any, where: str) -> int:
    condim = integer(1, 6)(value, where)
    if condim not in CONDIMS:
        raise InvalidArgumentError(f"{where} must be one of {', '.join(map(str, CONDIMS))} "
                                   f"(MuJoCo's contact dimensions), got {brief(value)}")
    return condim


CONDIMS = (1, 3, 4, 6)
# Where each default comes from (docs/PHYSICS.md tables them): MuJoCo's own unless it says
# "the daemon's", with why.
SOURCES = {
    "timestep": "MuJoCo's default (option timestep)",
    "gravity": "MuJoCo's default (option gravity)",
    "solver_iterations": "the daemon's (MuJoCo: 100): with cg and the early stop, the "
                         "Galton board's piles cost 8 times less per step at the same fidelity",
    "default_friction": "MuJoCo's default (geom friction 1)",
    "default_restitution": "MuJoCo's own contact, no restitution (geom solref as given)",
    "default_static_friction": "MuJoCo's default (geom friction 1)",
    "default_static_restitution": "MuJoCo's own contact, no restitution (geom solref as "
                                  "given)",
    "mujoco.solref": "MuJoCo's default (geom solref)",
    "mujoco.solimp": "MuJoCo's default (geom solimp)",
    "mujoco.condim": "MuJoCo's default (geom condim)",
    "mujoco.torsional_friction": "MuJoCo's default (geom friction[1])",
    "mujoco.rolling_friction": "MuJoCo's default (geom friction[2])",
    "mujoco.solver": "the daemon's (MuJoCo: newton): cheaper on piles, same fidelity",
    "mujoco.cone": "MuJoCo's default (option cone)",
    "mujoco.tolerance": "the daemon's (MuJoCo: 1e-8): the solver's early stop",
    "mujoco.ls_iterations": "the daemon's (MuJoCo: 50): with the early stop",
    "mujoco.noslip_iterations": "MuJoCo's default (option noslip_iterations)",
    "mujoco.integrator": "MuJoCo's default (option integrator)",
    "mujoco.threads": "the daemon's (MuJoCo: none): bit-identical results, faster crowds",
    "mujoco.sleep_tolerance": "the daemon's (MuJoCo: sleeping off): bodies at rest in "
                              "contact sleep, so settled crowds cost nothing",
    "mujoco.max_free_bodies": "the daemon's: a spawn's compile is quadratic in bodies",
    "mujoco.wake_balanced": "the daemon's (not in MuJoCo): a side effect of sleeping undone",
}

PARAMS: dict[str, ParamSpec] = with_sources({p.name: p for p in (
    shared("timestep", 0.002, "physics step"),
    shared("gravity", (0.0, 0.0, -9.81), "gravity vector, world frame"),
    shared("solver_iterations", 50, "constraint solver iterations (option iterations)"),
    shared("default_friction", 1.0,
           "sliding friction of moving bodies spawned without one, also when changed "
           "later; between two moving bodies a contact uses the larger value"),
    shared("default_restitution", 0.0,
           "restitution of moving bodies spawned without one, also when changed later; 0 "
           "means MuJoCo's own contact (mujoco.solref as given)"),
    shared("default_static_friction", 1.0,
           "sliding friction of static bodies (the scenery) spawned without one, also when "
           "changed later; a contact with a static body uses the static body's surface"),
    shared("default_static_restitution", 0.0,
           "restitution of static bodies spawned without one, also when changed later; a "
           "contact with a static body uses the static body's surface"),
    ParamSpec("mujoco.solref", (0.02, 1.0), "s, 1",
              "[timeconst, dampratio] of spawned bodies' contacts; a restitution e > 0 "
              "replaces the dampratio (see mujoco/mj_spec.py, damping_ratio)", _solref),
    ParamSpec("mujoco.solimp", (0.9, 0.95, 0.001, 0.5, 2.0), "",
              "[dmin, dmax, width, midpoint, power] impedance of spawned bodies' contacts",
              _solimp),
    ParamSpec("mujoco.condim", 3, "",
              "contact dimensions of spawned bodies: 1 frictionless, 3 sliding, 4 + spin "
              "(torsional), 6 + rolling friction; a contact takes the larger of its geoms'",
              _condim),
    ParamSpec("mujoco.torsional_friction", 0.005, "m",
              "torsional (spin) friction of spawned bodies: torque = value x normal force "
              "(condim 4 and 6)", number(0.0, 1.0)),
    ParamSpec("mujoco.rolling_friction", 0.0001, "m",
              "rolling friction of spawned bodies: torque = value x normal force (condim 6); "
              "value / radius is the rolling-resistance coefficient", number(0.0, 1.0)),
    ParamSpec("mujoco.solver", "cg", "", "constraint solver", choice(*SOLVERS)),
    ParamSpec("mujoco.cone", "pyramidal", "", "friction cone", choice(*CONES)),
    ParamSpec("mujoco.tolerance", 1e-4, "",
              "solver stops early once its relative improvement is below this (option "
              "tolerance)", number(0.0, 1.0)),
    ParamSpec("mujoco.ls_iterations", 5, "", "line-search iterations (newton, cg)",
              integer(1, 10_000)),
    ParamSpec("mujoco.noslip_iterations", 0, "", "no-slip solver iterations (0 = off)",
              integer(0, 10_000)),
    ParamSpec("mujoco.integrator", "euler", "", "numerical integrator", choice(*INTEGRATORS)),
    ParamSpec("mujoco.threads", 1, "",
              "worker threads MuJoCo adds to the physics thread while the world is crowded "
              "(from 400 contacts until below 200): collision detection and the constraint "
              "solver of separate islands run in parallel, with bit-identical results; "
              "0 = none", integer(0, 64)),
    ParamSpec("mujoco.sleep_tolerance", 0.005, "m/s",
              "island sleeping: trees in contact and slower than this fall asleep; a "
              "body touching nothing never sleeps (0 = sleeping off)",
              number(0.0, 10.0)),
    ParamSpec("mujoco.max_free_bodies", 12_000, "",
              "moving (free) bodies a spawn that must compile may bring the "
              "world to, parked ones included; past it the request is RESOURCE_LIMIT, "
              "nothing done: MuJoCo's compile is quadratic in them (about 12 s for 10,000 "
              "and 16 s for 12,000 on 2 cores), and a spawn that binds parked bodies needs "
              "no compile", integer(1, MAX_BODIES)),
    ParamSpec("mujoco.wake_balanced", True, "",
              "wake a ball that fell asleep on a single fixed round support near its top (a "
              "pin's apex or shoulder, within 30 degrees) and keep it awake until it leaves, "
              "for at most 5 s: a real ball cannot rest there alone, and one pinned by a "
              "neighbour creeps (mujoco/sleep_guard.py)", flag),
)}, SOURCES)
CONTACT_PARAMS = frozenset({"timestep", "default_friction", "default_restitution",
                            "default_static_friction", "default_static_restitution",
                            "mujoco.solref", "mujoco.solimp", "mujoco.condim",
                            "mujoco.torsional_friction", "mujoco.rolling_friction"})
