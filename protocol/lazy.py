"""Names a package exports but imports only when first used (PEP 562), so that a program
that needs a few of them (a command line's ``--help``) does not load numpy, Zenoh or
ZeroMQ for the rest."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping, MutableMapping
from typing import Any


def lazy_exports(package: str, sources: Mapping[str, tuple[str, ...]],
                 namespace: MutableMapping[str, Any]) -> Callable[[str], Any]:
    """A module ``__getattr__`` for ``package`` that imports each name from its module
    (``sources``: module -> names) on first use and keeps it in ``namespace``."""
    module_of = {name: module for module, names in sources.items() for name in names}

    def get(name: str) -> Any:
        module = module_of.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
        namespace[name] = value
        return value
    return get


def lazy_dir(sources: Mapping[str, tuple[str, ...]],
             namespace: Mapping[str, Any]) -> Callable[[], list[str]]:
    """A module ``__dir__`` that lists the lazy names beside those already loaded, so that
    ``dir()`` and tab completion show every export before its first use."""
    names = {name for exported in sources.values() for name in exported}

    def listing() -> list[str]:
        return sorted(names | set(namespace))
    return listing
