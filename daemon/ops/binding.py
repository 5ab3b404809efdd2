"""Binding a handler to its operation where the handler is written, so that a new
operation edits no central table: ``@handles("op")`` marks a handler
``(ctx, call, request) -> result``; ``@scene_op("op")`` marks a scene operation
``(world, request) -> result``, which handlers.py wraps as it wraps the others (the world
the request names; a ``scene`` event when the operation mutates).

Marking registers nothing: daemon/ops/handlers.py collects the marked functions of the
modules it lists (``OP_MODULES``), and ``check_bindings`` refuses at start-up an operation
with no handler, a handler with no operation, and an operation bound twice.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, TypeVar

F = TypeVar("F", bound=Callable[..., Any])

MARK = "galton_operation"  # the attribute a marked function carries


class Binding(NamedTuple):
    """Which operation a marked function serves, and whether it is a scene operation."""

    operation: str
    scene: bool


def handles(operation: str) -> Callable[[F], F]:
    """Mark a function ``(ctx, call, request) -> result`` as ``operation``'s handler."""
    return _mark(Binding(operation, scene=False))


def scene_op(operation: str) -> Callable[[F], F]:
    """Mark a function ``(world, request) -> result`` as ``operation``'s scene handler."""
    return _mark(Binding(operation, scene=True))


def _mark(binding: Binding) -> Callable[[F], F]:
    def mark(function: F) -> F:
        setattr(function, MARK, binding)
        return function
    return mark


def binding_of(value: object) -> Binding | None:
    """The binding a module attribute was marked with, if it was."""
    found = getattr(value, MARK, None)
    return found if isinstance(found, Binding) else None
