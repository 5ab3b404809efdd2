"""The ODE engine's parameters: name, default, unit, meaning and check of each.

The defaults are Webots' (R2023b), so that this engine runs the board as Webots runs it;
docs/ENGINES.md names the Webots source of every value. Two things differ from Webots on
purpose: the step (Webots' 32 ms lets balls pass through the pins and the floor of the
paper's board; ``WEBOTS_TIMESTEP`` is there as a named setting, the ``paper-webots`` board
uses it), and how two bodies' surfaces combine (Webots has one material pair for all).
"""

from __future__ import annotations

from galton.daemon.engines.params import (
    ParamSpec,
    choice,
    flag,
    integer,
    number,
    shared,
    with_sources,
)

WEBOTS_TIMESTEP = 0.032  # s: WorldInfo.basicTimeStep's default, 32 ms
# s: the paper board lost no ball at 2, 4 or 8 ms (43 of 100 at 32 ms); 2 ms keeps the
# explicit joint law stable at the gains robots use (a KUKA diverged at 4 ms).
DEFAULT_TIMESTEP = 0.002
STEPPERS = ("world", "quick")

# Where each default comes from (docs/ENGINES.md names the Webots file of each): Webots'
# set-up of ODE unless it says "the daemon's", with why.
SOURCES = {
    "timestep": "the daemon's (Webots: 32 ms, WorldInfo.basicTimeStep): the board loses "
                "balls at 32 ms, and robot gains need 2 ms",
    "gravity": "Webots' default (WorldInfo.gravity 9.81)",
    "solver_iterations": "ODE's QuickStep default 20 (unused by dWorldStep, Webots' stepper)",
    "default_friction": "Webots' contact default (ContactProperties.coulombFriction 1)",
    "default_restitution": "Webots' contact default (ContactProperties.bounce 0.5)",
    "default_static_friction": "Webots' contact default (coulombFriction 1)",
    "default_static_restitution": "Webots' contact default (bounce 0.5)",
    "ode.stepper": "Webots' (dWorldStep, WbSimulationCluster.cpp)",
    "ode.cfm": "Webots' default (WorldInfo.CFM)",
    "ode.erp": "Webots' default (WorldInfo.ERP)",
    "ode.contact_soft_cfm": "Webots' contact default (ContactProperties.softCFM)",
    "ode.soft_cfm_step": "the daemon's: Webots' soft CFM at every step as at Webots' 32 ms",
    "ode.contact_soft_erp": "Webots' contact default (ContactProperties.softERP)",
    "ode.bounce_velocity": "Webots' contact default (ContactProperties.bounceVelocity)",
    "ode.max_contacts": "Webots' MAX_CONTACT_JOINTS (WbSimulationCluster.cpp)",
    "ode.auto_disable": "Webots' (bodies at rest sleep, WbOdeContext.cpp)",
    "ode.disable_time": "Webots' default (WorldInfo.physicsDisableTime)",
    "ode.disable_linear_threshold": "Webots' default "
                                    "(WorldInfo.physicsDisableLinearThreshold)",
    "ode.disable_angular_threshold": "Webots' default "
                                     "(WorldInfo.physicsDisableAngularThreshold)",
}

PARAMS: dict[str, ParamSpec] = with_sources({spec.name: spec for spec in (
    shared("timestep", DEFAULT_TIMESTEP, "Simulated time per step (Webots' default "
           f"basicTimeStep is {WEBOTS_TIMESTEP} s: the paper-webots board sets it)."),
    shared("gravity", (0.0, 0.0, -9.81), "Gravity vector, world frame."),
    shared("solver_iterations", 20, "Iterations of QuickStep (ode.stepper quick); "
           "dWorldStep, Webots' stepper, solves exactly and ignores it."),
    shared("default_friction", 1.0, "Coulomb friction of moving bodies that set none, "
           "now and after a change (Webots' contact default 1). Between two moving bodies "
           "a contact takes the larger value."),
    shared("default_restitution", 0.5, "Bounce of moving bodies that set none, now "
           "and after a change (Webots' contact default 0.5). Between two moving bodies a "
           "contact takes the larger value."),
    shared("default_static_friction", 1.0, "Coulomb friction of static bodies (the "
           "scenery) that set none; a contact with a static body uses the static body's "
           "surface."),
    shared("default_static_restitution", 0.5, "Bounce of static bodies that set none; "
           "a contact with a static body uses the static body's surface."),
    ParamSpec("ode.stepper", "world", "", "world: dWorldStep, the exact (big-matrix) solver "
              "Webots steps with; quick: dWorldQuickStep, iterative (its random constraint "
              "order is seeded before every step, so runs replay).", choice(*STEPPERS)),
    ParamSpec("ode.cfm", 1e-5, "", "World constraint force mixing (WorldInfo.CFM).",
              number(0, 1)),
    ParamSpec("ode.erp", 0.2, "", "World error reduction (WorldInfo.ERP).", number(0, 1)),
    ParamSpec("ode.contact_soft_cfm", 0.001, "", "Contact softness (ContactProperties."
              "softCFM): with soft_erp, a spring of soft_erp / (timestep x soft_cfm) N/m.",
              number(0, 1)),
    ParamSpec("ode.soft_cfm_step", WEBOTS_TIMESTEP, "s", "The step ode.contact_soft_cfm is "
              "meant for. ODE softens a contact's solve by soft_cfm / timestep, so Webots' "
              "0.001, made for 32 ms, takes most of the bounce at small steps (a 0.5 bounce "
              "gives 0.26 at 2 ms); the engine uses soft_cfm x timestep / this, which bounces "
              "as Webots does at every step and is Webots' own value at 32 ms. 0: soft CFM as "
              "given.", number(0, 1)),
    ParamSpec("ode.contact_soft_erp", 0.2, "", "Contact error reduction (ContactProperties."
              "softERP).", number(0, 1)),
    ParamSpec("ode.bounce_velocity", 0.01, "m/s", "Contacts approaching slower than this do "
              "not bounce (ContactProperties.bounceVelocity).", number(0, 1000)),
    ParamSpec("ode.max_contacts", 10, "", "Contact joints per pair of geoms at most (Webots' "
              "MAX_CONTACT_JOINTS).", integer(1, 64)),
    ParamSpec("ode.auto_disable", True, "", "Put bodies at rest to sleep, as Webots does; a "
              "contact with a moving body wakes them.", flag),
    ParamSpec("ode.disable_time", 1.0, "s", "Time a body must be idle before it sleeps "
              "(WorldInfo.physicsDisableTime).", number(0, 1000)),
    ParamSpec("ode.disable_linear_threshold", 0.01, "m/s", "Idle below this speed "
              "(WorldInfo.physicsDisableLinearThreshold).", number(0, 1000)),
    ParamSpec("ode.disable_angular_threshold", 0.01, "rad/s", "Idle below this spin "
              "(WorldInfo.physicsDisableAngularThreshold).", number(0, 1000)),
)}, SOURCES)

SURFACE_DEFAULTS = frozenset({"default_friction", "default_restitution",
                              "default_static_friction", "default_static_restitution"})


def default_keys(static: bool) -> tuple[str, str]:
    """The parameters a body that sets no friction or restitution follows."""
    if static:
        return "default_static_friction", "default_static_restitution"
    return "default_friction", "default_restitution"
