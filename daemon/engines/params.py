"""Engine parameters: named, typed, with units and defaults, set all-or-none.

Names shared by every engine are bare (``timestep``) and declared here once (``SHARED``:
their unit and range); engine-specific ones carry the engine's name as prefix
(``mujoco.solref``, ``pybullet.collision_margin``). Asking one engine for another engine's
parameter is FEATURE_UNSUPPORTED, not a silent no-op.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from galton.protocol.errors import (
    FeatureUnsupportedError,
    InvalidArgumentError,
    brief,
    did_you_mean,
)
from galton.protocol.model import finite_number, integer_in
from galton.protocol.vocabulary import ENGINE_NAMES

KNOWN_ENGINES = ENGINE_NAMES


@dataclass(frozen=True)
class ParamSpec:
    """One parameter: its default, unit, meaning, a checker returning the clean value, and
    where the default comes from (``source``: the simulator's own, or the daemon's and why;
    set by ``with_sources``)."""

    name: str
    default: Any
    unit: str
    doc: str
    check: Callable[[Any, str], Any]
    source: str = ""

    def describe(self) -> dict[str, Any]:
        default = list(self.default) if isinstance(self.default, tuple) else self.default
        return {"default": default, "unit": self.unit, "doc": self.doc, "source": self.source}


def with_sources(specs: Mapping[str, ParamSpec],
                 sources: Mapping[str, str]) -> dict[str, ParamSpec]:
    """The specs, each with where its default comes from; every parameter must have one
    (a world starts as its simulator sets it up, and says where it does not)."""
    missing = sorted(set(specs) - set(sources))
    unknown = sorted(set(sources) - set(specs))
    if missing or unknown:
        raise ValueError(f"parameter sources: missing {missing}, unknown {unknown}")
    return {name: replace(spec, source=sources[name]) for name, spec in specs.items()}


def number(low: float, high: float, *, low_open: bool = False) -> Callable[[Any, str], float]:
    def check(value: Any, where: str) -> float:
        return finite_number(value, where, low=low, high=high, low_open=low_open)
    return check


def integer(low: int, high: int) -> Callable[[Any, str], int]:
    def check(value: Any, where: str) -> int:
        return integer_in(value, where, low, high)
    return check


def vector(length: int, low: float, high: float) -> Callable[[Any, str], tuple[float, ...]]:
    def check(value: Any, where: str) -> tuple[float, ...]:
        if not isinstance(value, list | tuple) or len(value) != length:
            raise InvalidArgumentError(f"{where} must be a list of {length} numbers, "
                                       f"got {brief(value)}")
        return tuple(finite_number(v, f"{where}[{i}]", low=low, high=high)
                     for i, v in enumerate(value))
    return check


def choice(*options: str) -> Callable[[Any, str], str]:
    def check(value: Any, where: str) -> str:
        if value not in options:
            raise InvalidArgumentError(f"{where} must be one of {', '.join(options)}, "
                                       f"got {brief(value)}")
        return str(value)
    return check


def flag(value: Any, where: str) -> bool:
    if not isinstance(value, bool):
        raise InvalidArgumentError(f"{where} must be true or false, got {brief(value)}")
    return value


# The parameters every engine has: one unit and one range for all (docs/ENGINES.md's table
# compares them across engines); each engine gives its own default and says what the value
# means there, through ``shared``.
SHARED: dict[str, tuple[str, Callable[[Any, str], Any]]] = {
    "timestep": ("s", number(0, 1, low_open=True)),
    "gravity": ("m/s²", vector(3, -1000, 1000)),
    "solver_iterations": ("", integer(1, 10_000)),
    "default_friction": ("", number(0, 100)),
    "default_restitution": ("", number(0, 1)),
    "default_static_friction": ("", number(0, 100)),
    "default_static_restitution": ("", number(0, 1)),
}


def shared(name: str, default: Any, doc: str) -> ParamSpec:
    """A parameter every engine has, with this engine's default and meaning."""
    unit, check = SHARED[name]
    return ParamSpec(name, default, unit, doc, check)


def check_updates(engine: str, specs: Mapping[str, ParamSpec],
                  updates: Mapping[str, Any]) -> dict[str, Any]:
    """Validate every update before any is applied; return the clean values."""
    if not isinstance(updates, Mapping):
        raise InvalidArgumentError(f"params must be a map of name to value, got {brief(updates)}")
    clean: dict[str, Any] = {}
    for name, value in updates.items():
        spec = specs.get(name)
        if spec is None:
            prefix = str(name).split(".", 1)[0]
            if "." in str(name) and prefix in KNOWN_ENGINES and prefix != engine:
                raise FeatureUnsupportedError(
                    f"parameter {brief(name)} belongs to the {prefix} engine; this daemon runs "
                    f"{engine}")
            raise InvalidArgumentError(
                f"unknown parameter {brief(name)}{did_you_mean(str(name), specs)}; "
                f"known: {', '.join(sorted(specs))}")
        clean[name] = spec.check(value, f"params.{name}")
    return clean
