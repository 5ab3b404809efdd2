"""Regenerate the parameter tables of docs/ENGINES.md from the engines' own specs.

Usage: python docs/make_engines_md.py   (rewrites docs/ENGINES.md in place)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from galton.daemon.engines import ENGINE_CLASSES, create_engine

PAGE = Path(__file__).with_name("ENGINES.md")
HEADER = ("| parameter | default | unit | meaning | where the default comes from |\n"
          "| --- | --- | --- | --- | --- |\n")


def shown(value: Any) -> str:
    if isinstance(value, str | bool):
        return str(value)
    if isinstance(value, list | tuple):
        return str(list(value))
    return json.dumps(value)


def table(engine_name: str) -> str:
    engine = create_engine(engine_name)
    try:
        params = engine.capabilities().params
    finally:
        engine.close()
    return "\n".join(f"| `{name}` | `{shown(spec['default'])}` | {spec.get('unit') or '–'} | "
                     f"{spec['doc']} | {spec['source']} |" for name, spec in params.items())


def main() -> None:
    text = PAGE.read_text()
    for name in ENGINE_CLASSES:
        start = text.index(HEADER, text.index(f"## {name}")) + len(HEADER)
        end = text.find("\n\n", start)
        text = text[:start] + table(name) + (text[end:] if end >= 0 else "\n")
    PAGE.write_text(text)


if __name__ == "__main__":
    main()
