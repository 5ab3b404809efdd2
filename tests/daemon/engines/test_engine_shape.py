"""Every engine has one shape (issue 50): the same modules in every engine package, the
same names in them (PARAMS), and the features derived once in the base from what each
engine implements, pinned here per engine, so a feature dropped by accident fails here
instead of making the feature's tests skip."""

from __future__ import annotations

import ast
import importlib
import inspect
from pathlib import Path

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
ENGINES_DIR = Path(__file__).resolve().parents[3] / "daemon" / "engines"
# The modules every engine package has (docs/ARCHITECTURE.md, "Engines"); a feature the
# engine lacks is a module that says so (``ABSENT = FEATURE_...``), an engine that keeps no
# state in memory says so in fast_state.py.
SHAPE = {"__init__", "engine", "params", "spawn", "state", "joints", "models", "shapes",
         "contacts", "rays", "render", "snapshot", "fast_state"}
SNAPSHOT_SHAPE = {"__init__", "format"}  # snapshot/: take and restore; the data's layout
# What each engine has beyond the shape, by name: add to it on purpose.
EXTRAS = {
    "mujoco": {"body_extras", "clone", "compiled", "entities", "mj_spec", "model_setup",
               "observed", "parked", "poses", "props", "removal", "sleep_guard", "stepping",
               "teleport", "urdf", "wrench", "snapshot/arrays"},
    "pybullet": {"articulated", "bodies", "calls", "files", "frames", "mesh_files", "meshes",
                 "mjcf", "perception", "props", "ray_shapes", "rebuild", "robots",
                 "snapshot/arrays"},
    "ode": {"frames", "native", "trimesh"},
    "dart": {"frames", "mesh_files", "meshes", "rebuild"},
}
# The modules that hold an optional feature, and the feature.
FEATURE_MODULES = {"rays": "raycast", "render": "render"}
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


def modules_of(package: Path) -> set[str]:
    """The package's modules by name, those of its subpackages as ``sub/name``."""
    found = {p.stem for p in package.glob("*.py")}
    for sub in package.iterdir():
        if sub.is_dir() and (sub / "__init__.py").is_file():
            found.add(sub.name)
            found.update(f"{sub.name}/{p.stem}" for p in sub.glob("*.py")
                         if p.stem != "__init__")
    return found


def test_the_engine_packages_are_the_registered_engines() -> None:
    packages = {p.name for p in ENGINES_DIR.iterdir() if (p / "engine.py").is_file()}
    assert packages == set(ENGINE_CLASSES) == set(EXTRAS)


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_every_engine_package_has_exactly_the_shape_and_its_listed_extras(name: str) -> None:
    package = ENGINES_DIR / name
    wanted = SHAPE | {f"snapshot/{m}" for m in SNAPSHOT_SHAPE - {"__init__"}} | EXTRAS[name]
    assert modules_of(package) == wanted
    assert (package / "snapshot" / "__init__.py").is_file()  # one snapshot package


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_no_engine_writes_its_capabilities_or_a_feature_list(name: str) -> None:
    """capabilities() and the features are the base's (engines/base.py)."""
    for path in (ENGINES_DIR / name).rglob("*.py"):
        tree = ast.parse(path.read_text(), str(path))
        defined = {n.name for n in ast.walk(tree)
                   if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)}
        assigned = {t.id for n in ast.walk(tree) if isinstance(n, ast.Assign)
                    for t in n.targets if isinstance(t, ast.Name)}
        assert not {"capabilities", "features"} & defined, path
        assert "FEATURES" not in assigned, path


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_every_engine_class_is_composed_the_same_way(name: str) -> None:
    """One composition (docs/ARCHITECTURE.md, "How to add an engine"): the class is
    ``Engine``'s subclass alone, no mixin, the only class of its engine.py, and every method
    it has beyond the base's is written there; its parts are functions of the engine (or
    objects it holds) in the package's modules."""
    cls = engine_class(name)
    assert cls.__bases__ == (Engine,), cls.__bases__
    assert cls.__mro__[1:] == Engine.__mro__
    source = ENGINES_DIR / name / "engine.py"
    assert Path(inspect.getsourcefile(cls) or "") == source
    classes = [n.name for n in ast.parse(source.read_text()).body if isinstance(n, ast.ClassDef)]
    assert classes == [cls.__name__]
    for attr, value in vars(cls).items():
        function = value.fget if isinstance(value, property) else getattr(
            value, "__func__", value)
        if inspect.isfunction(function):
            written = inspect.unwrap(function)
            assert Path(inspect.getsourcefile(written) or "") == source, (attr, written)


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_every_engine_declares_its_parameters_in_params_dot_params(name: str) -> None:
    params = importlib.import_module(f"galton.daemon.engines.{name}.params")
    assert engine_class(name).param_specs is params.PARAMS


@pytest.mark.parametrize("name", sorted(ENGINE_CLASSES))
def test_a_feature_module_says_absent_exactly_when_the_engine_lacks_the_feature(name: str
                                                                                 ) -> None:
    features = engine_class(name).features()
    for module_name, feature in FEATURE_MODULES.items():
        module = importlib.import_module(f"galton.daemon.engines.{name}.{module_name}")
        absent = getattr(module, "ABSENT", None)
        assert absent in (None, feature), (name, module_name)
        assert (absent is None) == (feature in features), (name, module_name)


def test_the_engines_page_lists_each_engines_derived_features() -> None:
    """docs/ENGINES.md's "Features:" line under each engine's heading is what it derives."""
    page = (ENGINES_DIR.parents[1] / "docs" / "ENGINES.md").read_text()
    listed: dict[str, str] = {}
    engine = ""
    for line in page.splitlines():
        if line.startswith("## "):
            engine = line.split()[1]
        elif line.startswith("Features: "):
            listed[engine] = line
    assert listed == {name: f"Features: {', '.join(engine_class(name).features())}."
                      for name in ENGINE_CLASSES}


def test_every_engine_package_and_subpackage_is_installed() -> None:
    """pyproject.toml lists packages by name: a subpackage left out is missing from a wheel."""
    listed = (ENGINES_DIR.parents[1] / "pyproject.toml").read_text()
    for package in ENGINES_DIR.glob("*/**/__init__.py"):
        dotted = ".".join(("galton", *package.parent.relative_to(ENGINES_DIR.parents[1]).parts))
        assert f'"{dotted}"' in listed, dotted
