"""A restored world must agree with itself: the checks ``world_snapshot`` runs on a world
rebuilt from a blob before it replaces anything (issue 35, item 3).

A blob's digest says only that it was not damaged by accident: anyone can edit its body and
seal it again (galton-daemon --snapshot-key makes the seal a secret one). So the registry is
checked field by field, and against the engine rebuilt from the same blob: every entity the
registry names is one the engine holds (and no other), its state is readable and within the
world's limits, and a spawned body is static exactly when the engine gives it no mass. A
blob that fails any of it is INVALID_ARGUMENT, and the world it was meant to replace stays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from galton.daemon.world.world import World
from galton.protocol import BODY_SHAPES, EntityInfo, InvalidArgumentError, RemoteError
from galton.protocol.errors import brief
from galton.protocol.model import check_name
from galton.protocol.vocabulary import MODEL_SHAPES, SIZE_LAYOUT

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
    for value in (info.mass, info.friction, info.restitution):
        if value is not None and not _non_negative(value):
            _refuse(f"entity {info.name!r} has a property {brief(value)}")
    in_model = info.shape in MODEL_SHAPES
    if in_model != (info.model is not None) or (in_model and info.model not in names):
        _refuse(f"entity {info.name!r} names model {brief(info.model)}")


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


def _positive(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value > 0


def _non_negative(value: Any) -> bool:
    return isinstance(value, int | float) and math.isfinite(value) and value >= 0


def _refuse(why: str) -> None:
    raise InvalidArgumentError(f"restore.blob is not a consistent snapshot: {why}")
