"""Records of the physical-law suite: each measured number beside its closed form, its
tolerance and why, and whether it passed; serialised as results.json.

The client's ``galton.client.laws`` runs the experiments and fills these; the report
(``galton.analysis.laws_report``) reads only them, so a results.json alone rebuilds it.
"""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from galton.analysis.errors import RecordError

LAWS_FORMAT = 1  # results.json's layout; bumped when a field changes meaning


@dataclass(frozen=True)
class Check:
    """One number an experiment measured, against its closed form: it passes when
    |value − theory| <= tolerance. ``value`` None: the engine could not run it (``note``)."""

    law: str  # the experiment's key, e.g. "free-fall"
    quantity: str  # what was measured, e.g. "drop after 1 s"
    unit: str
    theory: float
    value: float | None
    tolerance: float
    why: str  # why this tolerance
    note: str = ""

    @property
    def error(self) -> float | None:
        return None if self.value is None else self.value - self.theory

    @property
    def passed(self) -> bool:
        error = self.error
        return error is not None and math.isfinite(error) and abs(error) <= self.tolerance

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "error": self.error, "passed": self.passed}

    @classmethod
    def from_dict(cls, body: dict[str, Any]) -> Check:
        try:
            value = body["value"]
            return cls(law=str(body["law"]), quantity=str(body["quantity"]),
                       unit=str(body["unit"]), theory=float(body["theory"]),
                       value=None if value is None else float(value),
                       tolerance=float(body["tolerance"]), why=str(body["why"]),
                       note=str(body.get("note", "")))
        except (KeyError, TypeError, ValueError) as error:
            raise RecordError(f"a law check in results.json is malformed ({error!r}): "
                              f"{body!r}") from error


@dataclass
class EngineLaws:
    """Every check of one engine, with the step it ran at and the series worth plotting
    (name -> {"t": [...], "y": [...]})."""

    engine: str
    engine_version: str
    timestep: float
    gravity: float
    checks: list[Check] = field(default_factory=list)
    series: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    wall_s: float = 0.0

    @property
    def passed(self) -> int:
        return sum(check.passed for check in self.checks)

    def to_dict(self) -> dict[str, Any]:
        return {"engine": self.engine, "engine_version": self.engine_version,
                "timestep": self.timestep, "gravity": self.gravity,
                "checks": [c.to_dict() for c in self.checks], "series": self.series,
                "wall_s": self.wall_s, "passed": self.passed, "total": len(self.checks)}

    @classmethod
    def from_dict(cls, body: dict[str, Any]) -> EngineLaws:
        try:
            return cls(engine=str(body["engine"]), engine_version=str(body["engine_version"]),
                       timestep=float(body["timestep"]), gravity=float(body["gravity"]),
                       checks=[Check.from_dict(c) for c in body["checks"]],
                       series={str(k): {"t": list(v["t"]), "y": list(v["y"])}
                               for k, v in body.get("series", {}).items()},
                       wall_s=float(body.get("wall_s", 0.0)))
        except (KeyError, TypeError, ValueError) as error:
            raise RecordError(f"an engine's laws in results.json are malformed ({error!r})"
                              ) from error


@dataclass
class LawResults:
    """The suite's outcome over every engine run, and how it was run."""

    engines: list[EngineLaws]
    config: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {"format": LAWS_FORMAT, "config": self.config,
                "engines": [e.to_dict() for e in self.engines]}

    @classmethod
    def from_dict(cls, body: dict[str, Any]) -> LawResults:
        if not isinstance(body, dict) or body.get("format") != LAWS_FORMAT:
            raise RecordError(f"not a law-suite results.json of format {LAWS_FORMAT}")
        return cls(engines=[EngineLaws.from_dict(e) for e in body["engines"]],
                   config=dict(body.get("config", {})))

    def save(self, path: Path) -> None:
        path.write_text(json.dumps(self.to_dict(), indent=1, allow_nan=True) + "\n")

    @classmethod
    def load(cls, path: Path) -> LawResults:
        try:
            return cls.from_dict(json.loads(path.read_text()))
        except (OSError, json.JSONDecodeError) as error:
            raise RecordError(f"cannot read law results {path}: {error}") from error

    def rows(self) -> list[tuple[str, str]]:
        """Every (law, quantity) measured by any engine, in the order first run."""
        seen: dict[tuple[str, str], None] = {}
        for engine in self.engines:
            for check in engine.checks:
                seen.setdefault((check.law, check.quantity), None)
        return list(seen)

    def check(self, engine: str, law: str, quantity: str) -> Check | None:
        for record in self.engines:
            if record.engine == engine:
                for check in record.checks:
                    if (check.law, check.quantity) == (law, quantity):
                        return check
        return None
