"""Trial records and the results file (results.json): plain, JSON-safe, self-describing.

Every trial keeps the exact engine settings and board/run configuration that produced it, so
a report can be re-rendered, and a result re-run, from results.json alone.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from galton.analysis.errors import RecordError

RESULTS_SCHEMA = 1
RELEASE_MODES = ("all-at-once", "stream")
LOSS_REASONS = ("below_floor", "outside_cavity", "tunnelled", "nan")


def json_safe(value: Any) -> Any:
    """Plain JSON types: numpy scalars/arrays unwrapped, tuples as lists, NaN/inf as None."""
    if isinstance(value, dict):
        return {str(k): json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple | np.ndarray):
        return [json_safe(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value)]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _zero_losses() -> dict[str, int]:
    return dict.fromkeys(LOSS_REASONS, 0)


@dataclass
class TrialRecord:
    """One trial: one engine, one ball count, one repetition. Scores are None until scored."""

    engine: str
    engine_version: str
    board: str
    balls: int
    repetition: int
    seed: int
    release: str
    counts: list[int]
    settled: int
    lost: int = 0
    lost_by_reason: dict[str, int] = field(default_factory=_zero_losses)
    unsettled: int = 0
    sim_time: float = 0.0
    wall_time: float = 0.0
    rtf: float | None = None
    cpu_percent_mean: float | None = None
    peak_rss_bytes: int | None = None
    settings: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    chi2: float | None = None
    p_asymptotic: float | None = None
    p_monte_carlo: float | None = None
    daemon: str = ""  # the instance that ran it ("" where not recorded: before pools)

    def __post_init__(self) -> None:
        self.counts = [int(c) for c in self.counts]
        self.lost_by_reason = {**_zero_losses(), **{k: int(v) for k, v in
                                                    self.lost_by_reason.items()}}
        self.validate()

    @property
    def rows(self) -> int:
        """Pin rows of the board: one fewer than the bins."""
        return len(self.counts) - 1

    @property
    def lost_percent(self) -> float:
        """Lost balls as a percentage of the balls released in this trial."""
        return 100.0 * self.lost / self.balls if self.balls else 0.0

    def validate(self) -> None:
        """Raise RecordError when the ball accounting or a field does not add up."""
        where = f"trial {self.engine} balls={self.balls} repetition={self.repetition}"
        if self.release not in RELEASE_MODES:
            raise RecordError(f"{where}: release {self.release!r} is not one of {RELEASE_MODES}")
        if len(self.counts) < 2 or min(self.counts) < 0:
            raise RecordError(f"{where}: counts must be >= 2 non-negative bins: {self.counts}")
        if sum(self.counts) != self.settled:
            raise RecordError(
                f"{where}: settled={self.settled} but the bins hold {sum(self.counts)} balls")
        if self.settled + self.lost + self.unsettled != self.balls:
            raise RecordError(
                f"{where}: settled {self.settled} + lost {self.lost} + unsettled "
                f"{self.unsettled} must equal the {self.balls} balls released")
        if sum(self.lost_by_reason.values()) != self.lost:
            raise RecordError(
                f"{where}: lost_by_reason {self.lost_by_reason} sums to "
                f"{sum(self.lost_by_reason.values())}, not lost={self.lost}")

    def to_dict(self) -> dict[str, Any]:
        """A JSON-safe dict (numpy types unwrapped, non-finite floats as None)."""
        safe: dict[str, Any] = json_safe(asdict(self))
        return safe

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TrialRecord:
        """Build from ``to_dict`` output; unknown or missing fields raise RecordError."""
        if not isinstance(data, dict):
            raise RecordError(f"a trial record must be a JSON object, got {type(data).__name__}")
        known = {f.name for f in fields(cls)}
        unknown = set(data) - known
        if unknown:
            raise RecordError(f"trial record has unknown fields {sorted(unknown)}")
        try:
            return cls(**data)
        except TypeError as exc:
            raise RecordError(f"trial record is incomplete or mistyped: {exc}") from exc


@dataclass
class ExperimentResults:
    """All trials of one benchmark run, with what is needed to trust and re-run them."""

    trials: list[TrialRecord] = field(default_factory=list)
    date: str = ""
    host: str = ""
    versions: dict[str, str] = field(default_factory=dict)
    command: str = ""
    extra: dict[str, Any] = field(default_factory=dict)
    # The machines that ran the trials, by daemon instance (capabilities' ``host``).
    hosts: dict[str, dict[str, Any]] = field(default_factory=dict)
    # Where the trials ran: {"kind": "local"}, {"kind": "pool", ...} or {"kind": "ray", ...}
    # (empty in results written before executors were recorded).
    executor: dict[str, Any] = field(default_factory=dict)
    schema: int = RESULTS_SCHEMA

    def to_dict(self) -> dict[str, Any]:
        """JSON-safe dict; trials as a list of trial dicts."""
        body = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "trials"}
        safe: dict[str, Any] = json_safe({**body, "trials": [t.to_dict() for t in self.trials]})
        return safe

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ExperimentResults:
        """Inverse of ``to_dict``; a newer schema or a bad field raises RecordError."""
        if not isinstance(data, dict) or not isinstance(data.get("trials"), list):
            raise RecordError("results must be a JSON object with a 'trials' list")
        if data.get("schema", RESULTS_SCHEMA) > RESULTS_SCHEMA:
            raise RecordError(
                f"results schema {data['schema']} is newer than this reader ({RESULTS_SCHEMA})")
        meta = {k: data[k] for k in ("date", "host", "versions", "command", "extra", "hosts",
                                     "executor", "schema") if k in data}
        return cls(trials=[TrialRecord.from_dict(t) for t in data["trials"]], **meta)

    def to_json(self, path: str | Path) -> Path:
        """Write strict JSON (no NaN) to ``path``; return the path."""
        path = Path(path)
        text = json.dumps(self.to_dict(), indent=2, allow_nan=False)
        path.write_text(text + "\n", encoding="utf-8")
        return path

    @classmethod
    def from_json(cls, path: str | Path) -> ExperimentResults:
        """Read a results.json written by ``to_json``."""
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as exc:
            raise RecordError(f"cannot read results from {path}: {exc}") from exc
        return cls.from_dict(data)


def has_curve(trials: Sequence[TrialRecord]) -> bool:
    """Whether the trials ran at two ball counts at least (a curve versus balls: the RTF
    and footprint plots; one count would draw one point)."""
    return len({t.balls for t in trials}) >= 2
