"""calibrate in the SDK: what the daemon fitted (``CalibrationResult``), the request's
arguments, and an observation read from a recording (client/sdk/recording.py).

>>> seen = observed_in(Recording.load(Path("slide.npz")))
>>> fit = sim.calibrate({"box.friction": (0.05, 1.5)}, *seen)
>>> fit.fitted["box.friction"], fit.intervals["box.friction"], fit.predictions
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from galton.client.sdk.recording import Recording
from galton.protocol import POSE_WIDTH, InvalidArgumentError, Reply, pack_f64
from galton.protocol.operations import CalibrateReply
from galton.protocol.replies import decode_result


@dataclass(frozen=True)
class CalibrationResult:
    """The fitted values, an interval for each (the search's last spread), the position
    error (m) before and after, and what the search cost."""

    fitted: dict[str, float]
    intervals: dict[str, tuple[float, float]]
    error_before: float
    error_after: float
    predictions: int
    generations: int
    steps: int
    converged: bool
    applied: bool
    batches: int = 0  # batches of futures the predictions ran in

    @classmethod
    def from_reply(cls, reply: Reply) -> CalibrationResult:
        r = decode_result(CalibrateReply, reply.result)
        return cls(dict(r.fitted), {k: (v[0], v[1]) for k, v in r.intervals.items()},
                   r.error_before, r.error_after, r.predictions, r.generations, r.steps,
                   r.converged, r.applied, r.batches)

    def to_json(self) -> dict[str, Any]:
        """What ``galton-client calibrate --json`` prints."""
        return {"fitted": self.fitted,
                "intervals": {k: list(v) for k, v in self.intervals.items()},
                "error_before": self.error_before, "error_after": self.error_after,
                "predictions": self.predictions}


@dataclass(frozen=True)
class Observed:
    """Bodies seen at times: (samples,) times in seconds, (samples, bodies, 7) poses (a
    NaN row: not seen then); the first sample is where the prediction starts."""

    names: list[str]
    times: np.ndarray
    poses: np.ndarray


def observed_in(recording: Recording, names: Sequence[str] | None = None) -> Observed:
    """A recording's moving bodies (or ``names``) as an observation; samples that repeat
    an earlier time (the world was paused) are left out."""
    chosen = list(names) if names is not None else [
        info.name for info in recording.infos if not info.static and info.shape != "link"]
    if not chosen:
        raise InvalidArgumentError("the recording holds no moving body to calibrate on")
    index = [recording.names.index(name) for name in chosen]
    times = np.asarray(recording.times, float)
    # A world recorded while paused repeats its time: each time is kept once, the first.
    later = np.concatenate([[True], times[1:] > np.maximum.accumulate(times)[:-1]])
    return Observed(chosen, times[later], np.asarray(recording.poses, float)[later][:, index])


def calibrate_args(fit: Mapping[str, Sequence[float]], names: Sequence[str],
                   times: ArrayLike, poses: ArrayLike, twists: ArrayLike | None,
                   options: dict[str, Any]) -> dict[str, Any]:
    times_array = np.asarray(times, float).reshape(-1)
    poses_array = np.asarray(poses, float)
    if poses_array.size != len(times_array) * len(names) * POSE_WIDTH:
        raise InvalidArgumentError(f"calibrate: poses of shape {poses_array.shape} are not "
                                   f"{len(times_array)} samples of {len(names)} bodies")
    args: dict[str, Any] = {
        "names": list(names), "times": pack_f64(times_array),
        "poses": pack_f64(poses_array.reshape(-1, POSE_WIDTH)),
        "fit": {name: [float(bounds[0]), float(bounds[1])] for name, bounds in fit.items()},
        **{k: v for k, v in options.items() if v is not None}}
    if twists is not None:
        args["twists"] = pack_f64(np.asarray(twists, float).reshape(-1, 6))
    return args


# A parameter's bounds when the caller names none (galton-client calibrate --fit alone).
DEFAULT_BOUNDS: dict[str, tuple[float, float]] = {
    "friction": (0.0, 2.0), "restitution": (0.0, 0.95), "mass": (0.01, 100.0),
    "damping": (0.0, 10.0), "gravity": (0.0, 20.0)}


def bounds_for(fit: Sequence[str], given: Mapping[str, tuple[float, float]]
               ) -> dict[str, tuple[float, float]]:
    """Each fitted parameter's bounds: given, or its property's default."""
    unknown = sorted(set(given) - set(fit))
    if unknown:
        raise InvalidArgumentError(f"bounds given for {unknown[0]!r}, which is not fitted")
    chosen = {}
    for name in fit:
        prop = name.rpartition(".")[2]
        if name not in given and prop not in DEFAULT_BOUNDS:
            raise InvalidArgumentError(f"{name!r}: no default bounds for {prop!r}; give them")
        chosen[name] = given.get(name) or DEFAULT_BOUNDS[prop]
    return chosen


def trigger_calibration(spec: Mapping[str, Any]) -> dict[str, Any]:
    """A compare trigger's ``calibrate`` on the wire: its ``fit`` bounds as [low, high]
    lists, the other fields (apply, max_predictions, population, seed) as given (the
    daemon checks them, as it checks calibrate's)."""
    if "fit" not in spec:
        raise InvalidArgumentError("compare: a trigger's calibrate needs its fit "
                                   "({parameter: (low, high)})")
    wire = dict(spec)
    wire["fit"] = {name: [float(bound) for bound in bounds]
                   for name, bounds in spec["fit"].items()}
    return wire
