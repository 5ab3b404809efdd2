"""Regenerate the parameter tables of docs/ENGINES.md, and the defaults tables of
docs/PHYSICS.md (default and where it comes from, between ``<!-- defaults:ENGINE -->``
markers), from the engines' own specs.

Usage: python docs/make_engines_md.py   (rewrites both pages in place)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from galton.daemon.engines import ENGINE_CLASSES, create_engine

PAGE = Path(__file__).with_name("ENGINES.md")
PHYSICS = Path(__file__).with_name("PHYSICS.md")
DEFAULTS_HEADER = "| parameter | default | where it comes from |\n| --- | --- | --- |\n"
HEADER = ("| parameter | default | unit | meaning | where the default comes from |\n"
          "| --- | --- | --- | --- | --- |\n")


def shown(value: Any) -> str:
    if isinstance(value, str | bool):
        return str(value)
    if isinstance(value, list | tuple):
        return str(list(value))
    return json.dumps(value)


def params_of(engine_name: str) -> dict[str, Any]:
    engine = create_engine(engine_name)
    try:
        return dict(engine.capabilities().params)
    finally:
        engine.close()


def table(engine_name: str) -> str:
    return "\n".join(f"| `{name}` | `{shown(spec['default'])}` | {spec.get('unit') or '–'} | "
                     f"{spec['doc']} | {spec['source']} |"
                     for name, spec in params_of(engine_name).items())


def defaults_table(engine_name: str) -> str:
    """PHYSICS.md's table of an engine's defaults: value (with unit) and source."""
    return DEFAULTS_HEADER + "\n".join(
        f"| `{name}` | `{shown(spec['default'])}`{' ' + spec['unit'] if spec.get('unit') else ''}"
        f" | {spec['source']} |" for name, spec in params_of(engine_name).items()) + "\n"


def marked(engine_name: str) -> tuple[str, str]:
    return f"<!-- defaults:{engine_name} -->\n", f"<!-- /defaults:{engine_name} -->"


def main() -> None:
    text = PAGE.read_text()
    for name in ENGINE_CLASSES:
        start = text.index(HEADER, text.index(f"## {name}")) + len(HEADER)
        end = text.find("\n\n", start)
        text = text[:start] + table(name) + (text[end:] if end >= 0 else "\n")
    PAGE.write_text(text)
    physics = PHYSICS.read_text()
    for name in ENGINE_CLASSES:
        opening, closing = marked(name)
        start = physics.index(opening) + len(opening)
        physics = physics[:start] + defaults_table(name) + physics[physics.index(closing, start):]
    PHYSICS.write_text(physics)


if __name__ == "__main__":
    main()
