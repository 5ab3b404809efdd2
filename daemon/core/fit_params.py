"""The parameters calibrate fits, named as the request names them: ``<body>.<property>``
(a body's name, or a glob for a group set alike) with property ``friction``,
``restitution`` or ``mass``; ``gravity`` (its magnitude, along the world's gravity); and
``<joint>.damping`` (a 1-DOF joint's own damping, or a glob of joints set alike) on the
engines that set it (Engine.set_joint_damping)."""

from __future__ import annotations

import fnmatch
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from galton.daemon.engines.base import (
    FEATURE_UPDATE_FRICTION,
    FEATURE_UPDATE_MASS,
    FEATURE_UPDATE_RESTITUTION,
    Engine,
)
from galton.daemon.world.world import World
from galton.protocol import (
    BodyProperties,
    FeatureUnsupportedError,
    InvalidArgumentError,
    NotFoundError,
)
from galton.protocol.errors import brief, did_you_mean
from galton.protocol.vocabulary import MAX_FRICTION, MAX_GAIN, MAX_MASS

GRAVITY = "gravity"
MAX_GRAVITY = 1000.0  # m/s², the gravity parameter's own bound (engines/params.py)
# Each body property: its column in Engine.properties, the feature that sets it, its range.
BODY_PROPERTIES: dict[str, tuple[int, str, float, float]] = {
    "mass": (0, FEATURE_UPDATE_MASS, 0.0, MAX_MASS),
    "friction": (1, FEATURE_UPDATE_FRICTION, 0.0, MAX_FRICTION),
    "restitution": (2, FEATURE_UPDATE_RESTITUTION, 0.0, 1.0),
}
DAMPING = "damping"  # a joint's, N·m·s/rad or N·s/m
MAX_DAMPING = MAX_GAIN  # as a target's kd


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter: its name, the bodies it sets (joints for damping, none for
    gravity), its bounds."""

    name: str
    prop: str
    bodies: tuple[str, ...]
    low: float
    high: float

    def to_unit(self, value: float) -> float:
        return (value - self.low) / (self.high - self.low)

    def from_unit(self, unit: float) -> float:
        return self.low + float(np.clip(unit, 0.0, 1.0)) * (self.high - self.low)


def parameters(world: World, fit: Mapping[str, Sequence[float]]) -> list[Parameter]:
    """The request's ``fit`` as parameters of this world, or a typed refusal naming the
    first that cannot be fitted (unknown body or property, bounds out of range)."""
    return [_parameter(world, name, float(bounds[0]), float(bounds[1]))
            for name, bounds in fit.items()]


def _parameter(world: World, name: str, low: float, high: float) -> Parameter:
    if name == GRAVITY:
        _check_bounds(name, low, high, 0.0, MAX_GRAVITY)
        return Parameter(name, GRAVITY, (), low, high)
    target, dot, prop = name.rpartition(".")
    if not dot or not target:
        raise InvalidArgumentError(f"calibrate.fit: {brief(name)} is neither "
                                   "'<body>.<property>' nor 'gravity'")
    if prop == DAMPING:
        _check_bounds(name, low, high, 0.0, MAX_DAMPING)
        return Parameter(name, DAMPING, _joints(world, name, target), low, high)
    if prop not in BODY_PROPERTIES:
        known = [*BODY_PROPERTIES, DAMPING]
        raise InvalidArgumentError(f"calibrate.fit: {brief(name)} names no property "
                                   f"{brief(prop)}{did_you_mean(prop[:64], known)}; it fits "
                                   f"{', '.join(BODY_PROPERTIES)}")
    _, feature, floor, ceiling = BODY_PROPERTIES[prop]
    if feature not in world.engine.capabilities().features:
        raise FeatureUnsupportedError(f"the {world.engine.name} engine cannot fit "
                                      f"{brief(name)}: it does not change a body's {prop}",
                                      {"parameter": name})
    _check_bounds(name, low, high, floor, ceiling)
    bodies = _bodies(world, target, prop)
    return Parameter(name, prop, bodies, low, high)


def _check_bounds(name: str, low: float, high: float, floor: float, ceiling: float) -> None:
    positive = floor == 0.0 and name.endswith(".mass")  # a mass must be > 0
    if not (low < high) or low < floor or high > ceiling or (positive and low <= 0.0):
        raise InvalidArgumentError(
            f"calibrate.fit[{brief(name)}]: bounds [{low:g}, {high:g}] must be low < high "
            f"within {'(' if positive else '['}{floor:g}, {ceiling:g}]",
            {"parameter": name, "bounds": [low, high]})


def _bodies(world: World, target: str, prop: str) -> tuple[str, ...]:
    if target in world.entities:
        found = [target]
    else:
        found = [n for n in world.entities if fnmatch.fnmatchcase(n, target)]
    if not found:
        raise NotFoundError(f"calibrate.fit: no entity {brief(target)}"
                            f"{did_you_mean(target[:64], list(world.entities))}",
                            {"missing": [target]})
    static = [n for n in found if world.entities[n].info.static]
    if prop == "mass" and static:
        raise InvalidArgumentError(f"calibrate.fit: entity {brief(static[0])} is static: it "
                                   "has no mass to fit")
    world.require_no_links(found, "calibrate", "a model is fitted as a whole")
    return tuple(found)


def _joints(world: World, name: str, target: str) -> tuple[str, ...]:
    """The 1-DOF joints a damping parameter names (a joint, or a glob), on an engine that
    sets a joint's damping (one that keeps the contract's refusal: FEATURE_UNSUPPORTED)."""
    if type(world.engine).set_joint_damping is Engine.set_joint_damping:
        raise FeatureUnsupportedError(f"the {world.engine.name} engine cannot fit "
                                      f"{brief(name)}: it does not set a joint's damping",
                                      {"parameter": name})
    table = world.joints.by_name
    found = [target] if target in table else [
        n for n in table if fnmatch.fnmatchcase(n, target) and table[n].scalar]
    if not found:
        raise NotFoundError(f"calibrate.fit: no joint {brief(target)}"
                            f"{did_you_mean(target[:64], list(table))}",
                            {"missing": [target]})
    world.joints.require_scalar(found, f"calibrate.fit[{brief(name)}]")
    return tuple(found)


def current_values(world: World, params: Sequence[Parameter]) -> dict[str, float]:
    """What each parameter is in this world now (a group: its first body's)."""
    values = {}
    for p in params:
        if p.prop == GRAVITY:
            values[p.name] = float(np.linalg.norm(world.engine.get_params()[GRAVITY]))
        elif p.prop == DAMPING:
            values[p.name] = world.joints.by_name[p.bodies[0]].damping
        else:
            column = BODY_PROPERTIES[p.prop][0]
            values[p.name] = float(world.engine.properties([p.bodies[0]])[0, column])
    return values


def apply_values(world: World, params: Sequence[Parameter], values: Mapping[str, float]
                 ) -> None:
    """Set each parameter to its value in this world (gravity keeps its direction; a world
    without gravity gets it along -z; a joint's damping through the World)."""
    for p in params:
        value = values[p.name]
        if p.prop == GRAVITY:
            now = np.asarray(world.engine.get_params()[GRAVITY], float)
            norm = float(np.linalg.norm(now))
            direction = now / norm if norm > 0 else np.array([0.0, 0.0, -1.0])
            world.engine.set_params({GRAVITY: [float(v) for v in direction * value]})
        elif p.prop == DAMPING:
            world.set_joint_damping(list(p.bodies), np.full(len(p.bodies), value),
                                    "calibrate")
        else:
            world.update(list(p.bodies), body_properties(p.prop, value))


def body_properties(prop: str, value: float) -> BodyProperties:
    """One body property (``mass``, ``friction`` or ``restitution``) as an update sets it."""
    if prop == "mass":
        return BodyProperties(mass=value)
    if prop == "friction":
        return BodyProperties(friction=value)
    return BodyProperties(restitution=value)
