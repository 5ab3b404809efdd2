"""The PyBullet engine's parameters: name, default, unit, meaning and check of each, and the
setPhysicsEngineParameter keyword of those that are world settings.

``configure_world`` and ``apply``, functions of the engine, hand values to PyBullet and to the
bodies they reach.

The contact defaults are PyBullet's own (restitution 0, friction 0.5, contacts made from
Bullet's 0.02 m, cone friction): a world starts as PyBullet sets it up. The Galton board
carries its own calibrated materials (docs/physics/pybullet.md, client/boards).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from galton.daemon.engines.params import ParamSpec, flag, number, shared, with_sources
from galton.daemon.engines.pybullet.bodies import margin_for

if TYPE_CHECKING:

    from galton.daemon.engines.pybullet.engine import PybulletEngine
    from galton.daemon.engines.pybullet.rebuild import Body

# Where each default comes from (docs/PHYSICS.md tables them): PyBullet's own (3.2.7,
# examples/SharedMemory/PhysicsServerCommandProcessor.cpp and Bullet's btContactSolverInfo)
# unless it says "the daemon's", with why.
SOURCES = {
    "timestep": "PyBullet's default (fixedTimeStep 1/240 s)",
    "gravity": "the daemon's (PyBullet: none): Earth's, as every engine here",
    "solver_iterations": "the daemon's (PyBullet: 50): 40 % faster on the Galton board "
                         "at the same fidelity",
    "default_friction": "PyBullet's default (lateralFriction 0.5)",
    "default_restitution": "PyBullet's default (restitution 0)",
    "default_static_friction": "PyBullet's default (lateralFriction 0.5)",
    "default_static_restitution": "PyBullet's default (restitution 0)",
    "pybullet.restitution_velocity_threshold": "Bullet's default "
                                               "(m_restitutionVelocityThreshold 0.2)",
    "pybullet.contact_breaking_threshold": "Bullet's default (gContactBreakingThreshold)",
    "pybullet.ccd_swept_sphere_radius": "PyBullet's default (no CCD)",
    "pybullet.collision_margin": "PyBullet's default (m_defaultCollisionMargin 0.001)",
    "pybullet.enable_cone_friction": "PyBullet's default (enableConeFriction 1)",
    "pybullet.erp": "Bullet's default (m_erp 0.2)",
    "pybullet.contact_erp": "PyBullet's default (m_erp2 0.08)",
    "pybullet.deterministic_overlapping_pairs": "the daemon's (Bullet: off): identical "
                                                "runs give identical results",
}

PARAMS: dict[str, ParamSpec] = with_sources({spec.name: spec for spec in (
    shared("timestep", 1 / 240, "Simulated time per step."),
    shared("gravity", (0.0, 0.0, -9.81), "Gravity vector, world frame."),
    shared("solver_iterations", 10, "Constraint solver iterations per step "
           "(numSolverIterations; PyBullet's own default is 50)."),
    shared("default_friction", 0.5, "Lateral friction of moving bodies that set "
           "none, now and after a change. PyBullet multiplies both bodies' values at a "
           "contact: 0.5 on both is mu = 0.25."),
    shared("default_restitution", 0.0, "Restitution of moving bodies that set "
           "none, now and after a change. PyBullet multiplies both bodies' values at a "
           "contact: 0.8275 on both is e = 0.685."),
    shared("default_static_friction", 0.5, "Lateral friction of static bodies (the "
           "scenery) that set none, now and after a change; combined with the other body's "
           "value as a product, like every PyBullet contact."),
    shared("default_static_restitution", 0.0, "Restitution of static bodies that "
           "set none, now and after a change; combined as a product."),
    ParamSpec("pybullet.restitution_velocity_threshold", 0.2, "m/s", "Contacts approaching "
              "slower than this do not bounce.", number(0, 1000)),
    ParamSpec("pybullet.contact_breaking_threshold", 0.02, "m", "Gap at which Bullet makes a "
              "contact before two solids touch. Such early contacts lose their bounce once a "
              "few steps old, so a slow ball bounces less off a plane, box or cylinder, the "
              "more so at small timesteps; 0.001 gives the same bounce at every speed and step.",
              number(0, 1, low_open=True)),
    ParamSpec("pybullet.ccd_swept_sphere_radius", 0.0, "m", "Continuous collision detection "
              "for every dynamic body (0 = off): about the smallest ball's radius. Acts on "
              "spawned bodies only (Bullet has no CCD for the multibodies of models).",
              number(0, 10)),
    ParamSpec("pybullet.collision_margin", 0.001, "m", "Margin of spawned boxes, cylinders "
              "and planes: rounds box edges, capped at half the smallest half size. Spheres "
              "and capsules keep their radius as margin; models keep theirs.", number(0, 1)),
    ParamSpec("pybullet.enable_cone_friction", True, "", "Implicit cone friction; false "
              "uses the cheaper pyramid approximation.", flag),
    ParamSpec("pybullet.erp", 0.2, "", "Error reduction of non-contact constraints (the "
              "joints of loaded models).", number(0, 1)),
    ParamSpec("pybullet.contact_erp", 0.08, "", "Error reduction of contacts: the share of a "
              "penetration corrected per step.", number(0, 1)),
    ParamSpec("pybullet.deterministic_overlapping_pairs", True, "", "Sort overlapping pairs, "
              "so that identical runs give identical results.", flag),
)}, SOURCES)

# Parameters that are setPhysicsEngineParameter keywords (booleans go as 0/1).
WORLD_PARAMS = {
    "timestep": "fixedTimeStep",
    "solver_iterations": "numSolverIterations",
    "pybullet.restitution_velocity_threshold": "restitutionVelocityThreshold",
    "pybullet.contact_breaking_threshold": "contactBreakingThreshold",
    "pybullet.enable_cone_friction": "enableConeFriction",
    "pybullet.erp": "erp",
    "pybullet.contact_erp": "contactERP",
    "pybullet.deterministic_overlapping_pairs": "deterministicOverlappingPairs",
}

SURFACE_DEFAULTS = frozenset({"default_friction", "default_restitution",
                              "default_static_friction", "default_static_restitution"})


def default_keys(static: bool) -> tuple[str, str]:
    """The parameters a body that sets no friction or restitution follows."""
    if static:
        return "default_static_friction", "default_static_restitution"
    return "default_friction", "default_restitution"


def configure_world(engine: PybulletEngine) -> None:
    """Every setting of a fresh (or reset) world: resetSimulation forgets them all."""
    # The file cache keys on file names and keeps every file read: with temporary files
    # it only grows, and with a rewritten file it serves the old text.
    engine._bc.setPhysicsEngineParameter(enableFileCaching=0)
    apply(engine, engine._values)


def apply(engine: PybulletEngine, values: dict[str, Any]) -> None:
    """Hand changed values to PyBullet: world settings, then the bodies they reach."""
    world = {WORLD_PARAMS[k]: int(v) if isinstance(v, bool) else v
             for k, v in values.items() if k in WORLD_PARAMS}
    if world:
        engine._bc.setPhysicsEngineParameter(**world)
    if "gravity" in values:
        engine._bc.setGravity(*values["gravity"])
    bodies = list(engine.bodies.values())
    if values.keys() & SURFACE_DEFAULTS:
        follow_surface_defaults(engine, bodies, values)
    if "pybullet.ccd_swept_sphere_radius" in values:
        radius = values["pybullet.ccd_swept_sphere_radius"]
        for body in bodies:
            if not body.static:
                engine._change(body.uid, -1, ccdSweptSphereRadius=radius)
    if "pybullet.collision_margin" in values:
        done: set[tuple[str, tuple[float, ...]]] = set()
        for body in bodies:  # the shape is shared: one body per shape sets it for all
            if (body.shape, body.size) not in done:
                done.add((body.shape, body.size))
                set_margin(engine, body.uid, body.shape, body.size)


def follow_surface_defaults(engine: PybulletEngine, bodies: list[Body],
                            values: dict[str, Any]) -> None:
    """Bodies spawned without a friction or restitution take their kind's new default."""
    for body in bodies:
        friction_key, restitution_key = default_keys(body.static)
        if body.follows_friction and friction_key in values:
            body.friction = values[friction_key]
            engine._change(body.uid, -1, lateralFriction=body.friction)
        if body.follows_restitution and restitution_key in values:
            body.restitution = values[restitution_key]
            engine._change(body.uid, -1, restitution=body.restitution)


def set_margin(engine: PybulletEngine, uid: int, shape: str, size: tuple[float, ...]) -> None:
    margin = margin_for(shape, size, engine._values["pybullet.collision_margin"])
    if margin is not None:
        engine._change(uid, -1, collisionMargin=margin)
