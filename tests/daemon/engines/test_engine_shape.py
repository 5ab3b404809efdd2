"""Every engine has one shape (issue 50): the features it has are derived once in the base
from what it implements, and pinned here per engine, so a feature dropped by accident fails
here instead of making the feature's tests skip."""

from __future__ import annotations

import importlib

import pytest

from galton.daemon.engines import ENGINE_CLASSES, create_engine
from galton.daemon.engines.base import KNOWN_FEATURES, Engine
from galton.daemon.engines.geometry import DENSITY, volume
from galton.protocol import BodyGroup

ALL_FEATURES = ("spawn", "delete", "set_state", "update_mass", "update_friction",
                "update_restitution", "update_rgba", "load_model", "set_static_pose", "joints",
                "joint_targets", "target_position", "target_velocity", "target_effort",
                "wrench", "snapshot", "render", "raycast", "contacts", "spawn_inertia",
                "model_shapes")
# What each engine does today: change a line here only on purpose.
PINNED = {
    "mujoco": ALL_FEATURES,
    "pybullet": ALL_FEATURES,
    "ode": tuple(f for f in ALL_FEATURES if f != "render"),
    "dart": tuple(f for f in ALL_FEATURES if f not in ("render", "raycast")),
}


def engine_class(name: str) -> type[Engine]:
    module, cls = ENGINE_CLASSES[name].split(":")
    found: type[Engine] = getattr(importlib.import_module(module), cls)
    return found


def test_every_engine_is_pinned_and_the_protocol_knows_every_feature() -> None:
    assert set(PINNED) == set(ENGINE_CLASSES)
    assert ALL_FEATURES == KNOWN_FEATURES


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_an_engines_features_are_its_pinned_list(name: str) -> None:
    assert engine_class(name).features() == PINNED[name]


def test_features_follow_what_an_engine_overrides() -> None:
    """Derived, not declared: an engine that stops overriding ``render`` stops listing it,
    and one that holds only some target modes lists only those."""
    base = engine_class("pybullet")
    without_render = type("NoRender", (base,), {"render": Engine.render,
                                                "target_modes": ("position",)})
    features = without_render.features()
    assert "render" not in features and "raycast" in features
    assert "target_position" in features and "target_velocity" not in features


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_every_engine_gives_a_massless_body_the_shared_density_times_its_volume(name: str
                                                                                ) -> None:
    """One formula (engines/geometry.py) for all four: a capsule's mass is the same."""
    engine = create_engine(name)
    try:
        engine.spawn([BodyGroup(shape="capsule", size=(0.1, 0.2), names=["c"],
                                poses=[[0, 0, 1, 0, 0, 0, 1]])])
        mass = engine.properties(["c"])[0, 0]
    finally:
        engine.close()
    assert mass == pytest.approx(DENSITY * volume("capsule", (0.1, 0.2)), rel=1e-12)
