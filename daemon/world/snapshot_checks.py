"""A restored world must agree with itself: the checks ``world_snapshot`` runs on a world
rebuilt from a blob before it replaces anything (issue 35, item 3).

A blob's digest says only that it was not damaged by accident: anyone can edit its body and
seal it again (galton-daemon --snapshot-key makes the seal a secret one). So the registry is
checked field by field, and against the engine rebuilt from the same blob: every entity the
registry names is one the engine holds (and no other), its state is readable and within the
world's limits, and a spawned body is static exactly when the engine gives it no mass. A
blob that fails any of it is INVALID_ARGUMENT, and the world it was meant to replace stays.

Every number in it obeys the bounds a request's does (issue 46: a re-sealed blob is
something a client sends): the registry's before any engine sees the blob, and what the
engine rebuilt from it (masses, surfaces, joint modes and states, poses) before the world
takes a step, on every engine alike. A value that lives only in an engine's own format
(targets, wrenches) is checked by that engine's restore, against the same constants.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NoReturn

import numpy as np

from galton.daemon.world.world import World
from galton.protocol import BODY_SHAPES, EntityInfo, InvalidArgumentError, RemoteError
from galton.protocol.errors import brief
from galton.protocol.model import check_name, quaternion_norms
from galton.protocol.vocabulary import (
    MAX_FRICTION,
    MAX_JOINT_POSITION,
    MAX_JOINT_SPEED,
    MAX_MASS,
    MIN_MASS,
    MODEL_SHAPES,
    QUATERNION_NORM_BAND,
    SIZE_LAYOUT,
    TARGET_MODES,
)

SOURCES = ("spawn", "model")


def check_infos(infos: Sequence[EntityInfo]) -> None:
    """Every registry entry well formed: names, shapes, sizes, flags, model references."""
    names = {info.name for info in infos}
    if len(names) != len(infos):
        _refuse("it names an entity twice")
    for info in infos:
        _check_info(info, names)


def _check_info(info: EntityInfo, names: set[str]) -> None:
    check_name(info.name, "the snapshot's entity name")
    if info.shape not in (*BODY_SHAPES, *MODEL_SHAPES):
        _refuse(f"entity {brief(info.name)} has shape {brief(info.shape)}")
    layout = SIZE_LAYOUT.get(info.shape)
    if layout is not None and (len(info.size) != len(layout) or not all(
            _positive(v) for v in info.size)):
        _refuse(f"entity {info.name!r} has size {brief(list(info.size))} for a {info.shape}")
    if not isinstance(info.static, bool) or info.source not in SOURCES:
        _refuse(f"entity {info.name!r} has a malformed static flag or source")
    if not all(isinstance(tag, str) for tag in info.tags):
        _refuse(f"entity {info.name!r} has a tag that is no string")
    if info.mass is not None:
        low = MIN_MASS if info.source == "spawn" else 0.0
        _within(info.mass, low, MAX_MASS, f"entity {info.name!r}'s mass", "MIN_MASS, MAX_MASS")
    if info.friction is not None:
        _within(info.friction, 0.0, MAX_FRICTION, f"entity {info.name!r}'s friction",
                "MAX_FRICTION")
    if info.restitution is not None:
        _within(info.restitution, 0.0, 1.0, f"entity {info.name!r}'s restitution", "a unit")
    in_model = info.shape in MODEL_SHAPES
    if in_model != (info.model is not None) or (in_model and info.model not in names):
        _refuse(f"entity {info.name!r} names model {brief(info.model)}")


def check_modes(modes: dict[Any, Any]) -> None:
    """The registry's joint modes: joint names to one of the target modes."""
    for joint, mode in modes.items():
        if not isinstance(joint, str) or mode not in TARGET_MODES:
            _refuse(f"joint {brief(joint)} holds target mode {brief(mode)}; one of "
                    f"{', '.join(TARGET_MODES)} expected")


def check_ends(ends: dict[Any, Any]) -> None:
    """The registry's wrench ends: body names to a step index (or None: held until cleared)."""
    for body, end in ends.items():
        if not isinstance(body, str) or not (end is None or (
                isinstance(end, int) and not isinstance(end, bool) and end >= 0)):
            _refuse(f"the wrench on {brief(body)} ends at step {brief(end)}")


def check_clock(clock: Any) -> tuple[int, tuple[int, float, float]]:
    """The registry's clock: steps are counts, the time base finite, its step positive."""
    if not isinstance(clock, dict):
        _refuse(f"its clock is {brief(clock)}")
    step: Any = clock.get("step")
    base_step: Any = clock.get("base_step")
    base_time: Any = clock.get("base_time")
    base_dt: Any = clock.get("base_dt")
    for value, what in ((step, "step"), (base_step, "base_step")):
        if isinstance(value, bool) or not isinstance(value, int) or value < 0:
            _refuse(f"its clock's {what} is {brief(value)}, no step count")
    _within(base_time, 0.0, math.inf, "its clock's base_time", "a time")
    _within(base_dt, 0.0, math.inf, "its clock's base_dt", "a step", low_open=True)
    return int(step), (int(base_step), float(base_time), float(base_dt))


def check_agrees(world: World) -> None:
    """The registry and the engine rebuilt from one blob describe one world."""
    names = list(world.entities)
    held = world.engine.entity_names()
    if held is not None and set(held) != set(names):
        odd = sorted(set(held) ^ set(names))
        _refuse(f"its registry and its engine state disagree on entity {odd[0]!r}")
    try:
        world.engine.get_states(names)
        masses = world.engine.properties(names)[:, 0] if names else np.zeros(0)
    except RemoteError as error:
        _refuse(f"its engine state cannot serve its registry ({error.message})")
    for info, mass in zip(world.entities.values(), masses.tolist(), strict=True):
        if info.info.source == "spawn" and info.info.static != math.isnan(mass):
            _refuse(f"entity {info.info.name!r} is {'static' if info.info.static else 'dynamic'} "
                    "in its registry, not in its engine state")
    if not world.engine.state_within(world.limits.max_position, world.limits.max_speed):
        _refuse("its state is beyond the world's limits (diverged)")
    check_rebuilt(world, names)


def check_rebuilt(world: World, names: list[str]) -> None:
    """What the engine made of the blob, within the protocol's bounds, whatever engine and
    format: a moving spawned body's mass, every surface, the joints' modes and states, the
    poses' quaternions (before a step: a 1e-300 kg body under a wrench aborted DART's)."""
    rows = world.engine.properties(names).tolist() if names else []
    for (name, entity), (mass, friction, restitution) in zip(
            world.entities.items(), rows, strict=True):
        if entity.info.source == "spawn" and not entity.info.static:
            _within(mass, MIN_MASS, MAX_MASS, f"entity {name!r}'s mass", "MIN_MASS, MAX_MASS")
        elif not math.isnan(mass):
            _within(mass, 0.0, math.inf, f"entity {name!r}'s mass", "a mass")
        if entity.info.source == "spawn":
            _within(friction, 0.0, MAX_FRICTION, f"entity {name!r}'s friction", "MAX_FRICTION")
            _within(restitution, 0.0, 1.0, f"entity {name!r}'s restitution", "a unit")
    if names:
        norms = quaternion_norms(world.engine.get_states(names)[0][:, 3:7])
        low, high = QUATERNION_NORM_BAND
        bad = ~((norms >= low) & (norms <= high))
        if bad.any():
            _refuse(f"entity {names[int(np.argmax(bad))]!r}'s quaternion has norm "
                    f"{float(norms[bad][0]):g}, outside [{low:g}, {high:g}] "
                    "(QUATERNION_NORM_BAND)")
    _check_joints(world)


def _check_joints(world: World) -> None:
    joints = world.engine.joints()
    for joint in joints:
        if joint.mode not in TARGET_MODES:
            _refuse(f"joint {joint.name!r} holds target mode {brief(joint.mode)}; one of "
                    f"{', '.join(TARGET_MODES)} expected")
        _within(joint.damping, 0.0, math.inf, f"joint {joint.name!r}'s damping", "a damping")
    scalar = [j.name for j in joints if j.scalar]
    if scalar:
        positions, speeds, _ = world.engine.get_joint_states(scalar)
        for values, bound, what in ((positions, MAX_JOINT_POSITION, "position"),
                                    (speeds, MAX_JOINT_SPEED, "speed")):
            for name, value in zip(scalar, values.tolist(), strict=True):
                _within(value, -bound, bound, f"joint {name!r}'s {what}",
                        f"MAX_JOINT_{what.upper()}")


def _positive(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value > 0


def _within(value: Any, low: float, high: float, what: str, bound: str,
            low_open: bool = False) -> None:
    """``value`` a finite number in [low, high] (``low_open``: above low), as a request's
    own must be; else refused, naming the field and the bound (``bound``: its constants)."""
    number = float(value) if isinstance(value, int | float) and not isinstance(
        value, bool) else math.nan
    if math.isfinite(number) and (number > low if low_open else number >= low) and \
            number <= high:
        return
    span = f"{'(' if low_open else '['}{low:g}, {high:g}]"
    details: dict[str, Any] = {"field": what}
    details.update({k: v for k, v in (("min", low), ("max", high)) if math.isfinite(v)})
    _refuse(f"{what} is {brief(value)}, outside the protocol's {span} ({bound})", details)


def _refuse(why: str, details: dict[str, Any] | None = None) -> NoReturn:
    raise InvalidArgumentError(f"restore.blob is not a consistent snapshot: {why}", details)
