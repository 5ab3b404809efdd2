"""The DART engine's parameters, each set as Gazebo Harmonic sets it through gz-physics'
``dartsim`` plugin (docs/ENGINES.md names the file each default comes from).

SDF's ``<surface>`` gives every collision friction ``<ode><mu>`` 1 and
``<bounce><restitution_coefficient>`` 0 unless it sets them; gz-physics hands both to DART
per shape (``dartsim/src/SDFFeatures.cc``), and DART combines a pair as the smaller
friction and the product of restitutions. gz-sim steps at SDF's ``max_step_size`` 1 ms
under SDF's gravity (0, 0, -9.8).
"""

from __future__ import annotations

from galton.daemon.engines.params import ParamSpec, choice, flag, shared, with_sources

DETECTORS = ("ode", "fcl", "bullet", "dart")

# Where each default comes from (docs/ENGINES.md names the gz-physics file of each):
# Gazebo Harmonic's set-up of DART (SDF's defaults, gz-physics' dartsim plugin).
SOURCES = {
    "timestep": "Gazebo's default (SDF max_step_size 1 ms)",
    "gravity": "Gazebo's default (SDF gravity 9.8)",
    "solver_iterations": "DART's default (PGS fallback 30)",
    "default_friction": "Gazebo's default (SDF <ode><mu> 1)",
    "default_restitution": "Gazebo's default (SDF restitution_coefficient 0)",
    "default_static_friction": "Gazebo's default (SDF <ode><mu> 1)",
    "default_static_restitution": "Gazebo's default (SDF restitution_coefficient 0)",
    "dart.collision_detector": "Gazebo's (gz-physics sets ODE's detector in every world)",
    "dart.sleep": "Gazebo's (DART 6.13 has no sleeping)",
}

PARAMS: dict[str, ParamSpec] = with_sources({spec.name: spec for spec in (
    shared("timestep", 0.001, "Simulated time per step (SDF max_step_size, "
           "Gazebo's default)."),
    shared("gravity", (0.0, 0.0, -9.8), "Gravity vector, world frame (SDF's "
           "default)."),
    shared("solver_iterations", 30, "Iterations of the PGS solver DART falls back on "
           "when its Dantzig solver fails (DART's default 30; Dantzig itself is a direct "
           "method)."),
    shared("default_friction", 1.0, "Friction coefficient of moving bodies that set "
           "none (SDF <ode><mu>, default 1). DART takes the smaller of a pair's two."),
    shared("default_restitution", 0.0, "Restitution of moving bodies that set none "
           "(SDF <bounce><restitution_coefficient>, default 0). DART multiplies a pair's "
           "two."),
    shared("default_static_friction", 1.0, "Friction coefficient of static bodies "
           "that set none (SDF's default 1)."),
    shared("default_static_restitution", 0.0, "Restitution of static bodies that "
           "set none (SDF's default 0)."),
    ParamSpec("dart.collision_detector", "ode", "", "Collision detector: ode (what "
              "gz-physics installs in every world), fcl (DART's own default, which turns "
              "capsules into spheres), bullet or dart.", choice(*DETECTORS)),
    ParamSpec("dart.sleep", False, "", "Put bodies at rest to sleep (DART 6.20's "
              "deactivation, on in DART by default). Off, as in Gazebo Harmonic's DART 6.13, "
              "which has none; a sleeping body's rest timer is not in snapshots.", flag),
)}, SOURCES)
