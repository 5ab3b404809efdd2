"""A MuJoCo entity's physical properties: ``update`` and ``properties``, as functions of the
engine, and the contact values written into the model and the spec.

Contacts: a contact takes the larger of its two geoms' frictions and the average of their
solref (MuJoCo's rules); restitution maps to solref as ``spec.damping_ratio`` says.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import state as mst
from galton.daemon.engines.mujoco.entities import BODY, Entity
from galton.protocol import BodyProperties, GaltonError

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine


def update(engine: MujocoEngine, names: Sequence[str], props: BodyProperties) -> None:
    """The mass first, the one change MuJoCo may refuse (its recompile); the rest
    cannot fail, so a refused mass leaves every property as it was."""
    engine.body_ids(names)
    if props.mass is not None:
        set_masses(engine, names, props.mass)
    for name in names:
        entity = engine.entities[name]
        entity.key = None  # no longer like its parked twins: deleting it removes it
        if props.friction is not None:
            entity.friction = props.friction
        if props.restitution is not None:
            entity.restitution = props.restitution
    if props.friction is not None or props.restitution is not None:
        apply_contacts(engine, names)
    if props.rgba is not None:
        engine.model.geom_rgba[engine.geom_ids(names)] = props.rgba
        for name in names:
            for geom in engine.entities[name].geoms():
                geom.rgba = props.rgba


def set_masses(engine: MujocoEngine, names: Sequence[str], mass: float) -> None:
    """Give each entity this total mass (a model's bodies scaled alike); one recompile,
    the spec's old values put back if MuJoCo refuses it."""
    m = engine.model
    undo: list[tuple[Any, str, Any]] = []
    for name in names:
        entity = engine.entities[name]
        if entity.source == "spawn" and not entity.body.explicitinertial:
            undo += ms.set_values(entity.body.first_geom(), mass=mass)
            continue  # a body with its own inertia (spawn's) is scaled as a model's is
        scale = mass / max(float(m.body_subtreemass[engine.ids[name]]), 1e-12)
        for body in [entity.body, *entity.body.find_all(BODY)]:
            bid = body.id
            undo += ms.set_values(body, mass=float(m.body_mass[bid]) * scale,
                                  inertia=m.body_inertia[bid] * scale,
                                  ipos=m.body_ipos[bid], iquat=m.body_iquat[bid],
                                  explicitinertial=True)
    try:
        engine.recompile()
    except GaltonError:
        for element, attribute, value in reversed(undo):
            setattr(element, attribute, value)
        raise


def apply_contacts(engine: MujocoEngine, names: Sequence[str]) -> None:
    """Write these entities' contact values into the model and the spec: friction
    (sliding, torsional, rolling), condim, solref, solimp.

    Spawned bodies follow the defaults where they were given none; a loaded model keeps
    its file's values except those set by ``update``.
    """
    m, v = engine.model, engine.values
    for name in names:
        e = engine.entities[name]
        spawned = e.source == "spawn"
        default_friction, default_restitution = ms.default_surface(e.static, v)
        friction = default_friction if e.friction is None and spawned else e.friction
        restitution = default_restitution if e.restitution is None and spawned \
            else e.restitution
        if friction is None and restitution is None:
            continue
        ms.write_contacts(m, e.geoms(), engine.geom_ids([name]), v, friction, restitution,
                          spawned)


def properties(engine: MujocoEngine, names: Sequence[str]) -> np.ndarray:
    """Mass from the compiled model (a model root's subtree, a link's own; NaN when
    static), the first geom's sliding friction (a link's own geoms only), and the nominal
    restitution: the one given, the default a spawned body follows, NaN for a model's own
    contacts (MuJoCo has no restitution as such)."""
    m, ids = engine.model, engine.body_ids(names)
    entities = [engine.entities[n] for n in names]
    alone = np.array([e.source != "model" for e in entities], dtype=bool)  # no subtree
    mass = np.where(alone, m.body_mass[ids], m.body_subtreemass[ids])
    mass[[e.static for e in entities]] = np.nan
    geoms = mst.first_geoms(m, ids, alone)
    friction = np.full(len(ids), np.nan)  # no geom (a model may have none at all): NaN
    friction[geoms >= 0] = m.geom_friction[geoms[geoms >= 0], 0]
    values = [restitution(e, engine.values) for e in entities]
    return np.column_stack([mass, friction, np.array(values, dtype=float)])


def restitution(e: Entity, values: dict[str, Any]) -> float:
    """The restitution an entity simulates: its own, its kind's default, or NaN."""
    if e.restitution is not None:
        return e.restitution
    if e.source == "spawn":
        return ms.default_surface(e.static, values)[1]
    return float("nan")
