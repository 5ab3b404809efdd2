"""The CLI's choices and list syntax, taken from the protocol's declarations.

Choices are enums built from ``galton.protocol`` (OPERATIONS, BODY_SHAPES, RESET_SCOPES),
so a bad one ("spawn cube") fails while the command line is parsed, exit code 2, naming the
valid ones, before any request is sent; a new choice in the protocol appears here by itself.
Type checkers see each as ``str`` (what a member is): typer needs the runtime enum.

One list syntax: several entity names are separate arguments; a list given to one option
is comma-separated in that one value (numbers, names or tags).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from enum import StrEnum
from typing import TYPE_CHECKING, Any, TypeAlias

import typer

from galton.protocol import BODY_SHAPES, RESET_SCOPES
from galton.protocol.operations import OPERATIONS

if TYPE_CHECKING:
    import numpy as np

LIST_HELP = "comma-separated"


def protocol_choices(op: str, arg: str) -> tuple[str, ...]:
    """The choices the protocol declares for one argument of one operation."""
    declared = OPERATIONS[op].arg(arg)
    if declared is None or not declared.choices:
        raise LookupError(f"the protocol declares no choices for {op}.{arg}")
    return declared.choices


def choice_enum(name: str, values: Sequence[str]) -> type[StrEnum]:
    """A StrEnum whose members are ``values`` (typer renders and checks it as a choice)."""
    make: Any = StrEnum  # the functional API with names known only at run time
    made: type[StrEnum] = make(name, {value: value for value in values})
    return made


if TYPE_CHECKING:
    Shape: TypeAlias = str
    Engine: TypeAlias = str
    ModelFormat: TypeAlias = str
    EntityKind: TypeAlias = str
    ResetScope: TypeAlias = str
    TargetMode: TypeAlias = str
else:
    Shape = choice_enum("Shape", BODY_SHAPES)
    Engine = choice_enum("Engine", protocol_choices("load_world", "engine"))
    ModelFormat = choice_enum("ModelFormat", protocol_choices("load_model", "format"))
    EntityKind = choice_enum("EntityKind", protocol_choices("list", "kind"))
    ResetScope = choice_enum("ResetScope", RESET_SCOPES)
    TargetMode = choice_enum("TargetMode", protocol_choices("set_joint_targets", "mode"))


def counted(count: int, one: str, many: str) -> str:
    """``1 entity``, ``2 entities``: a count with its noun."""
    return f"{count} {one if count == 1 else many}"


def split_list(text: str, where: str) -> list[str]:
    """The items of one comma-separated option value; empty items are an error."""
    items = [item.strip() for item in text.split(",")]
    if not all(items):
        raise typer.BadParameter(f"{where} takes a comma-separated list, got {text!r}")
    return items


def numbers(text: str, where: str) -> list[float]:
    """Comma-separated numbers of one option, e.g. ``0,0,1``."""
    try:
        return [float(item) for item in split_list(text, where)]
    except ValueError:
        raise typer.BadParameter(f"{where} must be comma-separated numbers, got {text!r}") \
            from None


def rows(text: str, count: int, width: int, where: str) -> np.ndarray:
    """``count`` rows of ``width`` numbers from one comma-separated value, row after row;
    one row alone is repeated for every body."""
    import numpy as np
    values = numbers(text, where)
    if len(values) == width:
        return np.tile(np.asarray(values, dtype=float), (count, 1))
    if len(values) != count * width:
        raise typer.BadParameter(
            f"{where} needs {width} numbers per body ({count} bodies: {count * width}, or "
            f"{width} for all), got {len(values)}")
    return np.asarray(values, dtype=float).reshape(count, width)


def assignments(items: Sequence[str] | None) -> dict[str, Any]:
    """NAME=VALUE arguments as a map; VALUE is read as JSON, else kept as a string."""
    out: dict[str, Any] = {}
    for item in items or ():
        name, sep, raw = item.partition("=")
        if not sep or not name:
            raise typer.BadParameter(f"{item!r} is not NAME=VALUE")
        try:
            out[name] = json.loads(raw)
        except json.JSONDecodeError:
            out[name] = raw
    return out
