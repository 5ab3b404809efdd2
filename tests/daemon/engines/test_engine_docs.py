"""docs/ENGINES.md lists every engine parameter with its current default, and
docs/PHYSICS.md each engine's defaults with where they come from."""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

from galton.daemon.engines import ENGINE_CLASSES
from galton.daemon.engines.params import SHARED

GENERATOR = Path(__file__).parents[3] / "docs" / "make_engines_md.py"


def test_engines_page_tables_match_the_engines_specs() -> None:
    spec = importlib.util.spec_from_file_location("make_engines_md", GENERATOR)
    assert spec is not None and spec.loader is not None
    generator = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(generator)
    page = generator.PAGE.read_text()
    physics = generator.PHYSICS.read_text()
    for name in ENGINE_CLASSES:
        assert generator.table(name) in page, f"run python docs/make_engines_md.py ({name})"
        opening, closing = generator.marked(name)
        assert opening + generator.defaults_table(name) + closing in physics, (
            f"run python docs/make_engines_md.py ({name})")


def test_every_engine_declares_the_shared_parameters_from_the_base() -> None:
    """timestep, gravity, ... have one unit and one range on every engine (engines/params.py)."""
    for engine in ENGINE_CLASSES:
        specs = importlib.import_module(f"galton.daemon.engines.{engine}.params").PARAMS
        for name, (unit, check) in SHARED.items():
            assert (specs[name].unit, specs[name].check) == (unit, check), (engine, name)
