"""Loading MJCF and URDF models into the MuJoCo world, as functions of the engine.

Every top-level body of the model is a model: its root becomes an entity, and so does every
other body of its subtree (a link). The parsed model is rigged first (``model_setup``: names,
a floating base, one actuator per joint); its joints are described once compiled
(``joints``). Attaching cannot be undone, so it is tried on a copy of the spec first.
"""

from __future__ import annotations

import logging
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from galton.daemon.engines.mujoco import joints as mj
from galton.daemon.engines.mujoco import mj_spec as ms
from galton.daemon.engines.mujoco import parked as mp
from galton.daemon.engines.mujoco import state as mst
from galton.daemon.engines.mujoco.entities import (
    MUJOCO_ERRORS,
    WORLD,
    Assets,
    Entity,
    asset_names,
    delete_assets,
    mujoco_error,
)
from galton.daemon.engines.mujoco.model_setup import (
    Facts,
    body_name,
    entity_name,
    ready_model,
    rename_attached,
)
from galton.daemon.engines.mujoco.state import JOINTED
from galton.daemon.engines.mujoco.urdf import parse_urdf
from galton.protocol import (
    EntityInfo,
    FeatureUnsupportedError,
    GaltonError,
    NameNotUniqueError,
)
from galton.protocol.vocabulary import MODEL_FORMATS

if TYPE_CHECKING:
    from galton.daemon.engines.mujoco.engine import MujocoEngine

log = logging.getLogger(__name__)
FORMATS = MODEL_FORMATS
# MuJoCo warns that a model attached without a prefix may not save back to XML: this world
# is never saved.
EMPTY_PREFIX = "Attaching a spec with an empty prefix"


def load_model(engine: MujocoEngine, fmt: str, text: str | None, path: str | None,
               prefix: str, fixed_base: bool = True) -> list[EntityInfo]:
    """Attach a model's bodies to the spec, tried on a copy first; one recompile. Each
    top-level body is a model: its root entity, then one entity per link of its subtree."""
    child, facts = parse(fmt, text, path, fixed_base)
    tops, parts = ms.model_names(child, prefix, facts.link_name)
    links = [n for names in parts for n in names]
    check_model_names(engine, [*tops, *links], world_link=bool(facts.renamed))
    size = try_attaching(engine, child, prefix, facts, f"the {fmt.upper()} model")
    enter(engine, child, prefix, facts, tops, parts, size)
    engine.models += len(tops)
    engine.parts.update(links)
    infos: list[EntityInfo] = []
    for name in tops:
        root = engine.ids[name]
        engine.loaded_joints.add_model(name, mj.describe_model(engine.model, root, name, prefix,
                                                         facts))
        infos.append(model_info(engine, name))
        infos += [link_info(engine, int(b), name)
                  for b in np.flatnonzero(engine.model.body_rootid == root)[1:]]
    return infos


def try_attaching(engine: MujocoEngine, child: mujoco.MjSpec, prefix: str, facts: Facts,
                  what: str) -> mujoco.MjModel:
    """The world compiled with the model on a copy of the spec (attaching cannot be
    undone); the compile's warnings go where MuJoCo's others go: to the log."""
    try:
        trial = engine.mj_spec.copy()
        with warnings.catch_warnings(record=True) as said:
            warnings.simplefilter("always")
            attach(trial, child.copy(), prefix, trial.worldbody.add_frame(), facts)
            size = trial.compile()
    except MUJOCO_ERRORS as exc:
        raise mujoco_error(exc, f"{what} does not fit this world") from exc
    for warning in said:
        if EMPTY_PREFIX not in str(warning.message):
            log.warning("MuJoCo: %s", warning.message)
    return size


def enter(engine: MujocoEngine, child: mujoco.MjSpec, prefix: str, facts: Facts,
          tops: list[str], parts: list[tuple[str, ...]], size: mujoco.MjModel) -> None:
    """Attach the model to the world's spec, record its roots and links, recompile; on a
    failure take it all out again (its bodies and what uses them, its assets)."""
    frame = engine.mj_spec.worldbody.add_frame()
    before = asset_names(engine.mj_spec)
    try:
        attach(engine.mj_spec, child, prefix, frame, facts)
        assets = Assets(asset_names(engine.mj_spec) - before, len(tops))
        for name, inner in zip(tops, parts, strict=True):
            body = engine.mj_spec.body(body_name(name))
            engine.entities[name] = Entity(body, static=bool(body.mocap), source="model",
                                            parts=inner, model=name, assets=assets)
            for link in inner:
                engine.entities[link] = Entity(engine.mj_spec.body(body_name(link)),
                                                static=False, source="link", model=name)
        engine.recompile(size.nbody, size.nv)
    except (GaltonError, *MUJOCO_ERRORS) as exc:
        for name in [*tops, *(n for names in parts for n in names)]:
            engine.entities.pop(name, None)
        mp.remove_frame(engine.mj_spec, frame)
        delete_assets(engine.mj_spec, asset_names(engine.mj_spec) - before)
        if isinstance(exc, GaltonError):
            raise
        raise mujoco_error(exc, "the model does not fit this world") from exc


def attach(spec: mujoco.MjSpec, child: mujoco.MjSpec, prefix: str, frame: Any,
           facts: Facts) -> None:
    """Attach the model under this frame, its bodies renamed as the facts say."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=EMPTY_PREFIX)
        spec.attach(child, prefix=prefix, frame=frame)
    rename_attached(spec, prefix, facts)


def parse(fmt: str, text: str | None, path: str | None,
          fixed_base: bool) -> tuple[mujoco.MjSpec, Facts]:
    """A model parsed and readied (model_setup.ready_model); URDF's base floats unless
    ``fixed_base``, MJCF's is as the file says."""
    if fmt == "mjcf":
        child, facts = ms.parse_mjcf(text, path), Facts()
    elif fmt == "urdf":
        child, facts = parse_urdf(text, path)
    else:
        raise FeatureUnsupportedError(f"model format {fmt!r} is not supported by MuJoCo "
                                      f"here; supported: {', '.join(FORMATS)}")
    try:
        ready_model(child, facts, float_base=fmt == "urdf" and not fixed_base, urdf=fmt == "urdf")
        ms.ready_tops(child, fmt)
    except MUJOCO_ERRORS as exc:
        raise mujoco_error(exc, f"the {fmt.upper()} model cannot be rigged") from exc
    return child, facts


def check_model_names(engine: MujocoEngine, names: Sequence[str], *,
                      world_link: bool = False) -> None:
    """Refuse a model whose bodies' names are taken, or the engine's own (but "world" for
    a URDF's world link, which MuJoCo knows by another name: ``model_setup.body_name``)."""
    for name in names:
        own = (name == WORLD and not world_link) or name.startswith(mp.PREFIX)
        if name in engine.entities or name in engine.parts or own:
            raise NameNotUniqueError(
                f"the model's body {name!r} has the name of a body already in the MuJoCo "
                "world; load it with another prefix")


def model_info(engine: MujocoEngine, name: str) -> EntityInfo:
    """A loaded entity as the World lists it; a jointed one's pose kept as its initial."""
    bid = engine.ids[name]
    entity = engine.entities[name]
    if engine.index.kind[bid] == JOINTED:
        poses, _ = mst.jointed_states(engine.model, engine.data, np.array([bid]))
        entity.initial_pose = poses[0]
    return EntityInfo(name=name, shape="model", static=entity.static,
                      mass=float(engine.model.body_subtreemass[bid]), source="model",
                      model=name)


def link_info(engine: MujocoEngine, bid: int, model: str) -> EntityInfo:
    """A model's link as the World lists it (its own mass)."""
    return EntityInfo(name=entity_name(engine.model.body(bid).name), shape="link",
                      mass=float(engine.model.body_mass[bid]), source="model", model=model)
